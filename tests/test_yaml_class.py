"""A class written only in YAML gets part-seeded segmentation and CAD scaling.

The bar stool below is not in the built-in ontology and no code knows its name: its
seat (65–85 cm) and footrest are marked as segmentation seeds, its seat as the part
CAD fitting scales a model by. Nothing else is needed.
"""

import numpy as np
import pytest

from ontodetect.cad import ModelLibrary, fit_object, hints_from_points, make_model, model_scale
from ontodetect.cad._models import sample_surface
from ontodetect.geometry._mesh import Mesh
from ontodetect.ontology import builtin_ontology, load_ontology
from ontodetect.segment import segment
from ontodetect.synth.furniture import make_furniture

BAR_STOOL = """\
format: ontodetect.ontology/1
classes:
  bar_stool:
    description: A backless seat at counter height with a footrest ring.
    prior: {rooms: seating}
    context: [table]
    cluster:
      rise: {max: 0.08, soft: 0.06}
      length: {max: 0.55, soft: 0.1}
      height: [0.6, 0.9]
    parts:
      seat:
        seed: seat                    # seeds a cluster the way a chair's seat does
        cad: seat                     # the model's seat height follows it
        tilt: {max: 6, soft: 5}
        height: [0.65, 0.85]
        length: [0.25, 0.45]
        width: [0.2, 0.45]
      footrest:
        seed: seat
        required: false
        missing: 0.8
        tilt: {max: 10, soft: 5}
        height: [0.3, 0.55]
    labeling:
      plane_size: {mean: 0.35, sigma: 0.1}
"""
SEAT_HEIGHT = 0.8


@pytest.fixture(scope="module")
def ontology(tmp_path_factory):
    path = tmp_path_factory.mktemp("onto") / "bar_stool.yaml"
    path.write_text(BAR_STOOL, encoding="utf-8")
    return load_ontology(path)


@pytest.fixture(scope="module")
def stool():
    # A 40 cm seat: the 30 cm seat of the smallest bar stools is at the least area
    # (``cluster.min_part_area``) that seeds a cluster.
    obj = make_furniture("stool-bar", 3, seat_height=SEAT_HEIGHT, seat_size=0.4, base="legs")
    pts = sample_surface(Mesh(obj.vertices, obj.triangles), spacing=0.01, rng=0)
    return obj, pts


def test_the_yaml_class_is_read_with_its_roles(ontology):
    cls = ontology["bar_stool"]
    assert cls.part("seat").seed == "seat" and cls.part("footrest").seed == "seat"
    assert cls.part("seat").cad == "seat" and cls.context == ("table",)
    # Its seats reach 85 cm: patches up to there now seed the way seats do.
    (seat, top), (builtin_seat, _) = ontology.seed_styles(), builtin_ontology().seed_styles()
    assert seat[0].name == "seat" and seat[1] == pytest.approx(0.85)
    assert builtin_seat[1] == pytest.approx(0.75) and top[0].name == "top"
    assert ("bar_stool", "table") in ontology.context_pairs()


def test_its_seat_seeds_a_cluster_in_a_generated_scene(ontology, stool, rng):
    _, pts = stool
    floor = np.c_[rng.uniform(-1.5, 1.5, (20000, 2)), np.zeros(20000)]
    scene = np.vstack([floor, pts])

    def seat_seed(onto):
        seg = segment(scene, fit_planes=False, seed=0, ontology=onto)
        labels = seg.labels_per_point()[len(floor) :]
        counts = np.bincount(labels[labels >= 0])
        best = int(counts.argmax())
        seeds = [p for p in seg[best].parts if abs(p.height - SEAT_HEIGHT) < 0.05]
        return seeds, counts[best] / len(pts)

    seeds, share = seat_seed(ontology)
    assert len(seeds) == 1 and seeds[0].kind == "seat"  # the bar stool's own seat seeds it
    assert seeds[0].rise == ontology.seeds["seat"].rise
    assert share >= 0.8
    # Without the class an 80 cm patch is a table top, which claims little below it.
    builtin, _ = seat_seed(None)
    assert all(p.kind == "top" for p in builtin)


def test_cad_fitting_scales_a_generic_model_by_its_declared_seat(ontology, stool):
    _, pts = stool
    low = make_furniture("stool-bar", 3, seat_height=0.66, base="legs")
    model = make_model(
        "bar-stool-generic", "bar_stool", [Mesh(low.vertices, low.triangles)], {"seat_height": 0.66}
    )
    hints = hints_from_points(pts, "bar_stool", ontology)
    assert hints.seat_center[2] == pytest.approx(SEAT_HEIGHT, abs=0.02)
    scale = model_scale(model, hints, ontology)
    assert scale[2] == pytest.approx(SEAT_HEIGHT / model.dims["seat_height"], abs=0.03)
    fit = fit_object(pts, "bar_stool", ModelLibrary([model]), ontology=ontology)
    assert fit.model == "bar-stool-generic" and fit.scale[2] == pytest.approx(scale[2], abs=0.03)
    # The built-in ontology knows no bar stool: its seat is sought where chairs' are.
    assert hints_from_points(pts, "bar_stool").seat_center is None or (
        hints_from_points(pts, "bar_stool").seat_center[2] < 0.76
    )


def test_its_context_rewards_a_bar_stool_beside_a_table(ontology):
    """The labelling's context term comes from the class's ``context``, not from its name."""
    from types import SimpleNamespace

    from ontodetect.labeling import label_clusters
    from ontodetect.ontology import ClusterScores

    def scores(**probs):
        probs = {name: 0.0 for name in ontology.names} | probs
        probs["none"] = max(0.0, 1 - sum(probs.values()))
        return ClusterScores(classes={}, probabilities=probs, best=max(probs, key=probs.get))

    amb = scores(bar_stool=0.40, table=0.40)
    planes = [[SimpleNamespace(length=0.8, width=0.5, color_mean=None)]] * 2  # a table's size
    centers = [[0.0, 0.0, 0.8], [0.5, 0.0, 0.9]]
    pair = [amb, scores(table=0.9)]
    alone = label_clusters(pair, planes, ontology)
    helped = label_clusters(pair, planes, ontology, centers=centers, context=0.3)
    assert alone[0].extra["class"] == "table" and helped[0].extra["class"] == "bar_stool"
