"""The environment prior from photographs: GIST, the calibrated classifier, its safe file
format, folders of images, and how P_N from images and from the scan combine."""

from __future__ import annotations

import json
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _images import TEXTURES, texture, write_training_folder
from ontodetect.environment import (
    MODEL_FORMAT,
    EnvironmentModel,
    GistParams,
    combine_room_priors,
    cross_validated_accuracy,
    gist,
    predict_environment,
    train_environment,
)
from ontodetect.errors import CorruptFileError, InvalidParameterError, ReadError
from ontodetect.io import write_array_archive
from ontodetect.ontology import room_categories

CATEGORIES = sorted(TEXTURES)


@pytest.fixture(scope="module")
def stripes():
    rng = np.random.default_rng(7)
    return texture("vertical", rng)


@pytest.fixture(scope="module")
def dataset():
    """GIST descriptors of 6 training and 3 held-out images per category."""
    rng = np.random.default_rng(3)
    train, test = [], []
    for name in CATEGORIES:
        for k in range(9):
            (train if k < 6 else test).append((gist(texture(TEXTURES[name], rng)), name))
    X = np.array([g for g, _ in train])
    Xt = np.array([g for g, _ in test])
    return X, [n for _, n in train], Xt, [n for _, n in test]


@pytest.fixture(scope="module")
def model(dataset):
    X, y, _, _ = dataset
    return EnvironmentModel(seed=0).fit(X, y)


# -- GIST ---------------------------------------------------------------------------------
def test_gist_has_512_finite_values(stripes):
    g = gist(stripes)
    assert g.shape == (512,) and g.dtype == np.float64
    assert np.all(np.isfinite(g)) and np.all(g >= 0) and g.max() > 0
    assert GistParams().length == 512


@settings(max_examples=12)
@given(k=st.floats(0.3, 3.0))
def test_gist_is_unchanged_by_a_global_brightness_scale(stripes, k):
    # 30..220 scaled by up to 3: no value clips, since the descriptor takes floats.
    np.testing.assert_allclose(gist(k * stripes), gist(stripes), rtol=0, atol=1e-9)


def test_gist_is_unchanged_by_an_offset_and_by_colour_copies(stripes):
    np.testing.assert_allclose(gist(stripes + 25.0), gist(stripes), atol=1e-9)
    rgb = np.dstack([stripes, stripes, stripes])
    np.testing.assert_allclose(gist(rgb), gist(stripes), atol=1e-12)


def test_gist_does_not_modify_its_input(stripes):
    before = stripes.copy()
    gist(stripes)
    assert np.array_equal(stripes, before)


def test_gist_tells_textures_apart():
    rng = np.random.default_rng(11)
    kinds = ("horizontal", "vertical", "checker")
    g = {k: [gist(texture(k, rng)) for _ in range(3)] for k in kinds}
    within = max(
        np.linalg.norm(a - b) for k in kinds for i, a in enumerate(g[k]) for b in g[k][i + 1 :]
    )
    between = min(
        np.linalg.norm(a - b)
        for i, k in enumerate(kinds)
        for m in kinds[i + 1 :]
        for a in g[k]
        for b in g[m]
    )
    assert between > within


def test_gist_of_a_flat_image_is_zero():
    assert not np.any(gist(np.full((40, 50), 90.0)))


def test_gist_settings_change_the_length_and_are_checked(stripes):
    params = GistParams(image_size=64, orientations=(4, 4), blocks=2)
    assert gist(stripes, params).shape == (params.length,) == (32,)
    with pytest.raises(InvalidParameterError, match="'blocks'"):
        GistParams(blocks=0)
    with pytest.raises(InvalidParameterError, match="'image_size'"):
        GistParams(image_size=8)
    with pytest.raises(InvalidParameterError, match="'orientations'"):
        GistParams(orientations=())


@pytest.mark.parametrize(
    "image",
    [np.zeros(10), np.zeros((1, 10)), np.full((8, 8), np.nan), np.zeros((2, 2, 2, 2))],
    ids=["1-d", "one row", "nan", "4-d"],
)
def test_gist_refuses_what_is_not_an_image(image):
    with pytest.raises(InvalidParameterError, match="'image'"):
        gist(image)


# -- the classifier ----------------------------------------------------------------------
def test_the_model_recognises_held_out_images(model, dataset):
    _, _, Xt, yt = dataset
    proba = model.predict_proba(Xt)
    np.testing.assert_allclose(proba.sum(axis=1), 1.0, atol=1e-12)
    predicted = [model.classes_[i] for i in proba.argmax(axis=1)]
    assert predicted == yt
    assert proba.max(axis=1).min() > 0.5


def test_the_same_images_and_seed_give_the_same_model(model, dataset):
    X, y, Xt, _ = dataset
    again = EnvironmentModel(seed=0).fit(X, y)
    assert np.array_equal(again.predict_proba(Xt), model.predict_proba(Xt))


@pytest.mark.parametrize("classes", [CATEGORIES, CATEGORIES[:2]], ids=["three", "two"])
def test_numpy_prediction_equals_scikit_learn(dataset, classes):
    from ontodetect.environment._model import _fit_calibrated

    X, y, Xt, _ = dataset
    keep = [i for i, n in enumerate(y) if n in classes]
    Xk, yk = X[keep], [y[i] for i in keep]
    model = EnvironmentModel(seed=0).fit(Xk, yk)
    codes = np.searchsorted(model.classes_, yk)
    mean, scale, fitted = _fit_calibrated(Xk, codes, C=1.0, seed=0)
    expected = fitted.predict_proba((Xt - mean) / scale)
    np.testing.assert_allclose(model.predict_proba(Xt), expected, rtol=0, atol=1e-9)


def test_room_probabilities_average_the_frames_and_sum_to_one(model, dataset):
    _, _, Xt, _ = dataset
    office = Xt[[i for i, n in enumerate(dataset[3]) if n == "office"]]
    rooms = model.room_probabilities(office)
    assert list(rooms) == sorted(rooms, key=rooms.get, reverse=True)
    assert next(iter(rooms)) == "office"
    assert sum(rooms.values()) == pytest.approx(1.0)
    per_frame = model.predict_proba(office).mean(axis=0)
    assert rooms["office"] == pytest.approx(per_frame[model.classes_.index("office")])


def test_an_alias_spreads_over_its_categories(dataset):
    X, y, Xt, yt = dataset
    labels = ["lounge" if n == "living_room" else n for n in y]
    model = EnvironmentModel(seed=0).fit(X, labels)
    assert "lounge" in model.classes_
    # living-room textures, trained as "lounge" (a sitting room or a waiting lounge)
    rooms = model.room_probabilities(Xt[[i for i, n in enumerate(yt) if n == "living_room"]])
    assert set(rooms) == {"living_room", "waiting_room", "kitchen", "office"}
    assert rooms["living_room"] == pytest.approx(rooms["waiting_room"])
    assert rooms["living_room"] + rooms["waiting_room"] > 0.5


@pytest.mark.parametrize(
    ("labels", "message"),
    [
        (["office"] * 18, "at least two room categories"),
        (["office"] * 17 + ["kitchen"], "at least 2 images per category"),
        (["office"] * 9 + ["spaceship"] * 9, "'room'"),
        (["office"] * 9 + ["Office"] * 9, "at least two room categories"),
        (["conference"] * 9 + ["conference_room"] * 9, "at least two room categories"),
        (["office"] * 3, "one name per descriptor"),
    ],
)
def test_training_refuses_what_cannot_be_learnt(dataset, labels, message):
    with pytest.raises(InvalidParameterError, match=message):
        EnvironmentModel().fit(dataset[0], labels)


def test_training_refuses_descriptors_of_another_length(dataset):
    with pytest.raises(InvalidParameterError, match="'descriptors'"):
        EnvironmentModel().fit(dataset[0][:, :100], dataset[1])
    with pytest.raises(InvalidParameterError, match="'C'"):
        EnvironmentModel(C=0).fit(dataset[0], dataset[1])


def test_cross_validated_accuracy_or_the_reason_it_is_missing(dataset):
    X, y, _, _ = dataset
    accuracy, note = cross_validated_accuracy(X, y)
    assert accuracy == 1.0 and "3-fold" in note
    keep = [i for i, n in enumerate(y) if i % 6 < 3]
    accuracy, note = cross_validated_accuracy(X[keep], [y[i] for i in keep])
    assert accuracy is None and "3 images" in note


# -- the model file ----------------------------------------------------------------------
def test_save_and_load_give_the_same_predictions(model, dataset, tmp_path, monkeypatch):
    path = model.save(tmp_path / "rooms.npz")

    def no_pickle(*args, **kwargs):
        raise AssertionError("the model loader unpickled something")

    monkeypatch.setattr(pickle, "loads", no_pickle)
    monkeypatch.setattr(pickle, "load", no_pickle)
    loaded = EnvironmentModel.load(path)
    monkeypatch.undo()
    _, _, Xt, _ = dataset
    np.testing.assert_allclose(loaded.predict_proba(Xt), model.predict_proba(Xt), atol=1e-9)
    assert loaded.classes_ == model.classes_ and loaded.gist == model.gist
    assert loaded.training_["images"] == {c: 6 for c in CATEGORIES}


def test_the_model_file_is_plain_arrays_and_json(model, tmp_path):
    path = model.save(tmp_path / "rooms.npz")
    with np.load(path, allow_pickle=False) as archive:
        header = json.loads(str(archive["header"]))
        assert header["format"] == MODEL_FORMAT
        assert header["classes"] == CATEGORIES
        assert header["gist"]["orientations"] == [8, 8, 8, 8]
        assert archive["coef"].shape[1:] == (3, 512)
        assert all(archive[k].dtype == np.float64 for k in archive.files if k != "header")


def _broken(tmp_path, model, **changes):
    path = model.save(tmp_path / "good.npz")
    with np.load(path, allow_pickle=False) as archive:
        header = json.loads(str(archive["header"]))
        arrays = {k: archive[k] for k in archive.files if k != "header"}
    header.update(changes.pop("header", {}))
    arrays.update(changes)
    for k in [k for k, v in arrays.items() if v is None]:
        del arrays[k]
    return write_array_archive(tmp_path / "bad.npz", header, arrays)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"header": {"format": "something/2"}}, "format 'something/2'"),
        ({"header": {"classes": ["office"]}}, "'classes'"),
        ({"header": {"classes": ["office", "kitchen", "spaceship"]}}, "unusable header"),
        ({"header": {"gist": {"blocks": -1}}}, "unusable header"),
        ({"coef": None}, "missing arrays: coef"),
        ({"mean": np.zeros(10)}, "'mean' has shape"),
        ({"scale": np.zeros(512)}, "not positive"),
        ({"intercept": np.full((3, 3), np.inf)}, "not finite"),
    ],
)
def test_a_damaged_model_file_is_one_clear_error(model, tmp_path, change, message):
    path = _broken(tmp_path, model, **change)
    with pytest.raises(CorruptFileError, match=message) as info:
        EnvironmentModel.load(path)
    assert str(path) in str(info.value)


def test_files_that_are_not_model_files(tmp_path):
    garbage = tmp_path / "garbage.npz"
    garbage.write_bytes(b"PK\x03\x04 not really a zip archive" * 10)
    with pytest.raises(CorruptFileError, match=r"garbage\.npz"):
        EnvironmentModel.load(garbage)
    pickled = tmp_path / "pickled.npz"
    np.savez(pickled, header=np.array(json.dumps({"format": MODEL_FORMAT})), x=np.array([{}]))
    with pytest.raises(ReadError, match="Python objects"):
        EnvironmentModel.load(pickled)
    no_header = tmp_path / "points.npz"
    np.savez(no_header, xyz=np.zeros((4, 3)))
    with pytest.raises(CorruptFileError, match="no 'header'"):
        EnvironmentModel.load(no_header)
    with pytest.raises(ReadError, match="no such model file"):
        EnvironmentModel.load(tmp_path / "missing.npz")


# -- folders of images -------------------------------------------------------------------
@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    root = write_training_folder(tmp_path_factory.mktemp("rooms"), per_category=4, seed=1)
    return root, train_environment(root, seed=0)


def test_training_on_a_folder_and_predicting_a_folder(trained, tmp_path):
    _, model = trained
    assert model.classes_ == tuple(CATEGORIES)
    assert model.training_["images"] == {c: 4 for c in CATEGORIES}
    assert model.training_["cv_accuracy"] is not None
    scene = write_training_folder(tmp_path, per_category=2, seed=99, categories=["kitchen"])
    rooms = predict_environment(scene / "kitchen", model)
    assert next(iter(rooms)) == "kitchen" and rooms["kitchen"] > 0.5
    files = sorted((scene / "kitchen").iterdir())
    one = predict_environment(files[0], model)
    two = predict_environment(files[1], model)
    mean = {c: (one[c] + two[c]) / 2 for c in one}
    assert rooms == pytest.approx(mean)
    saved = model.save(tmp_path / "m.npz")
    assert predict_environment([files[0], files[1]], saved) == pytest.approx(rooms)


@pytest.mark.parametrize(
    ("layout", "message"),
    [
        ({}, "holds no sub-folder"),
        ({"office": 3, "kitchen": 0}, "kitchen: holds no image"),
        ({"office": 3}, "one category only (office)"),
        ({"office": 3, "spaceship": 3}, "spaceship: not a room category or alias"),
        ({"office": 3, "kitchen": 1}, "kitchen: 1 image; each category needs at least 2"),
        ({"conference": 2, "conference_room": 2}, "the same category as"),
    ],
)
def test_a_training_folder_that_cannot_be_used(tmp_path, layout, message):
    rng = np.random.default_rng(0)
    from PIL import Image

    for name, count in layout.items():
        (tmp_path / name).mkdir()
        for k in range(count):
            Image.fromarray(texture("checker", rng).astype(np.uint8)).save(
                tmp_path / name / f"{k}.png"
            )
    with pytest.raises(ReadError) as info:
        train_environment(tmp_path)
    assert message in str(info.value)


def test_a_corrupt_image_is_named(tmp_path, model):
    root = write_training_folder(tmp_path, per_category=2, categories=["office", "kitchen"])
    bad = root / "kitchen" / "broken.jpg"
    bad.write_bytes(b"\xff\xd8\xff\xe0 this is not a JPEG at all" * 7)
    with pytest.raises(CorruptFileError, match=r"broken\.jpg: not a readable image"):
        train_environment(root)
    with pytest.raises(CorruptFileError, match=r"broken\.jpg"):
        predict_environment(bad, model)


def test_an_empty_scene_folder_is_named(tmp_path, model):
    (tmp_path / "empty").mkdir()
    with pytest.raises(ReadError, match="empty: holds no image"):
        predict_environment(tmp_path / "empty", model)
    with pytest.raises(InvalidParameterError, match="'model'"):
        predict_environment(np.zeros((8, 8)), EnvironmentModel())


# -- combining P_N from the scan and from images -----------------------------------------
def test_combining_multiplies_and_renormalises():
    scan = {"office": 0.5, "living_room": 0.5}
    images = {"office": 0.8, "living_room": 0.2}
    both = combine_room_priors(scan, images, floor=0.0)
    assert both["office"] == pytest.approx(0.8) and both["living_room"] == pytest.approx(0.2)
    assert set(both) == set(room_categories())
    assert list(both)[:2] == ["office", "living_room"]


def test_one_source_zero_does_not_veto_the_other():
    both = combine_room_priors({"living_room": 1.0}, {"office": 1.0})
    assert both["living_room"] == pytest.approx(both["office"])
    assert both["living_room"] > 0.45
    without_floor = combine_room_priors({"living_room": 1.0}, {"office": 1.0}, floor=0.0)
    assert without_floor["office"] == pytest.approx(1 / len(room_categories()))


def test_one_source_alone_is_returned_normalised():
    assert combine_room_priors({"office": 3, "lobby": 1}, None) == {"office": 0.75, "lobby": 0.25}
    assert combine_room_priors(None, None) is None


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (({"office": 1}, {"spaceship": 1}), "'room'"),
        (({"office": 1}, {"office": -1}), "room"),
    ],
)
def test_combining_checks_its_inputs(args, message):
    with pytest.raises(InvalidParameterError, match=message):
        combine_room_priors(*args)
    with pytest.raises(InvalidParameterError, match="'floor'"):
        combine_room_priors({"office": 1}, {"office": 1}, floor=1.0)


_weights = st.dictionaries(
    st.sampled_from(room_categories()), st.floats(0.01, 10.0), min_size=1, max_size=5
)


@given(scan=_weights, images=_weights, floor=st.floats(0.0, 0.5))
def test_combination_is_a_symmetric_distribution(scan, images, floor):
    both = combine_room_priors(scan, images, floor=floor)
    assert sum(both.values()) == pytest.approx(1.0)
    assert all(p >= 0 for p in both.values())
    assert combine_room_priors(images, scan, floor=floor) == pytest.approx(both)
