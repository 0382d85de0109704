"""A scene classifier on GIST descriptors: P_N from photographs (thesis §3.6, Tables 4.11–4.13).

One linear support vector machine per room category (one-vs-rest, as the thesis runs "24
classifiers"), on standardised GIST descriptors, with Platt's sigmoid calibration fitted on
held-out folds so that its scores are probabilities. Several photographs of one scene are
averaged, as the thesis averages the frames of a scene.

Training uses scikit-learn; prediction is a few lines of NumPy on the fitted numbers, so a
model file holds only arrays and JSON (never a pickle) and is checked when it is read.
"""

from __future__ import annotations

import math
import os
import warnings
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import expit

from .._progress import progress
from .._rules import POSITIVE, SEED, check_param
from .._version import __version__
from ..errors import CorruptFileError, InvalidParameterError, OntoDetectError, ReadError
from ..io import image_files, read_array_archive, read_image, write_array_archive
from ..ontology import room_distribution
from ._gist import GistParams, gist

__all__ = [
    "MODEL_FORMAT",
    "EnvironmentModel",
    "cross_validated_accuracy",
    "descriptors_of",
    "predict_environment",
    "train_environment",
]

#: Format tag of a model file's header.
MODEL_FORMAT = "ontodetect.environment-model/1"
#: Folds of the sigmoid calibration (fewer when a category has fewer images).
CALIBRATION_FOLDS = 3
#: Folds of the accuracy estimate shown after training (fewer when categories are small).
ACCURACY_FOLDS = 5
#: Images each category needs in each held-out fold for the accuracy estimate.
ACCURACY_MIN_PER_FOLD = 2
#: Images a category needs at least: one to fit on and one to calibrate on.
MIN_IMAGES_PER_CATEGORY = 2
#: Iterations of the linear SVM's solver (liblinear): ample for a few thousand images.
SVM_MAX_ITER = 10_000
#: Probabilities a hair above 1 after calibration are 1 (as scikit-learn does).
PROBABILITY_SLACK = 1e-5
_ARRAYS = ("mean", "scale", "coef", "intercept", "calibration_a", "calibration_b")


def _room_key(name: str) -> str:
    return str(name).strip().lower().replace("-", "_").replace(" ", "_")


def _class_name(name: str) -> str:
    """The name a class is trained under: the category an alias stands for when it stands
    for one (``conference`` -> ``conference_room``), else the alias itself (``bedroom``).
    Raises InvalidParameterError when ``name`` is neither a category nor an alias."""
    key = _room_key(name)
    rooms = room_distribution(key) or {}
    return next(iter(rooms)) if len(rooms) == 1 else key


class EnvironmentModel:
    """A calibrated scene classifier over room categories.

    Parameters
    ----------
    C : float
        Inverse regularisation strength of the linear SVMs.
    gist : GistParams, optional
        Settings of the GIST descriptor (the reference implementation's by default).
    seed : int
        Seed of the calibration folds and of the solver: the same images and seed give
        the same model.

    Attributes
    ----------
    classes_ : tuple of str
        The room names trained on (categories or aliases of Places205, see
        :func:`ontodetect.ontology.room_distribution`), sorted.
    mean_, scale_ : (d,) float
        Standardisation of the descriptors.
    coef_ : (folds, k, d) float
        Per calibration fold, the one-vs-rest SVM weights (k = 1 for two classes).
    intercept_, calibration_a_, calibration_b_ : (folds, k) float
        SVM intercepts and Platt's sigmoid ``p = 1 / (1 + exp(a * f + b))`` per class.
    training_ : dict
        Images per class and the cross-validated accuracy, for the record.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = np.r_[rng.normal(0, 1, (6, 512)), rng.normal(3, 1, (6, 512))]
    >>> model = EnvironmentModel().fit(X, ["office"] * 6 + ["kitchen"] * 6)
    >>> model.classes_
    ('kitchen', 'office')
    >>> bool(model.predict_proba(X[:1])[0, 1] > 0.5)
    True
    """

    def __init__(self, *, C: float = 1.0, gist: GistParams | None = None, seed: int = 0) -> None:
        self.C = C
        self.gist = gist
        self.seed = seed

    # -- fitting ------------------------------------------------------------------------
    def fit(self, descriptors: ArrayLike, labels: Sequence[str]) -> EnvironmentModel:
        """Fit on GIST descriptors ``(n, d)`` and their room names (``n`` strings).

        Raises
        ------
        InvalidParameterError
            Fewer than two classes, a class with fewer than two images, a name that is no
            room category or alias, or descriptors of the wrong length.
        """
        params = self.gist or GistParams()
        X, y, classes = self._check_training(descriptors, labels, params)
        mean, scale, fitted = _fit_calibrated(X, y, C=self.C, seed=self.seed)
        self._set_fitted(classes, params, mean, scale, _calibrated_arrays(fitted, len(classes)))
        counts = {c: int(np.sum(y == i)) for i, c in enumerate(classes)}
        self.training_ = {"images": counts, "cv_accuracy": None, "seed": self.seed, "C": self.C}
        return self

    def _check_training(
        self, descriptors: ArrayLike, labels: Sequence[str], params: GistParams
    ) -> tuple[NDArray[np.float64], NDArray[np.intp], tuple[str, ...]]:
        check_param("C", POSITIVE, self.C)
        check_param("seed", SEED, self.seed)
        X = np.asarray(descriptors, dtype=np.float64)
        if X.ndim != 2 or X.shape[1] != params.length:
            raise InvalidParameterError(
                "descriptors", f"an (n, {params.length}) array", f"shape {X.shape}"
            )
        if not np.all(np.isfinite(X)):
            raise InvalidParameterError("descriptors", "finite values", "NaN or infinity")
        known: dict[str, str] = {}
        for v in labels:
            if v not in known:
                known[v] = _class_name(v)  # checked against today's table of categories
        names = [known[v] for v in labels]
        if len(names) != len(X):
            raise InvalidParameterError(
                "labels", f"one name per descriptor ({len(X)})", f"{len(names)} names"
            )
        classes = tuple(sorted(set(names)))
        if len(classes) < 2:
            raise InvalidParameterError(
                "labels", "at least two room categories to tell apart", list(classes)
            )
        y = np.searchsorted(classes, names)
        for i, c in enumerate(classes):
            if np.sum(y == i) < MIN_IMAGES_PER_CATEGORY:
                raise InvalidParameterError(
                    f"labels[{c!r}]",
                    f"at least {MIN_IMAGES_PER_CATEGORY} images per category "
                    "(one to fit, one to calibrate)",
                    f"{int(np.sum(y == i))} image",
                )
        return X, y, classes

    def _set_fitted(
        self,
        classes: tuple[str, ...],
        params: GistParams,
        mean: NDArray[np.float64],
        scale: NDArray[np.float64],
        arrays: dict[str, NDArray[np.float64]],
    ) -> None:
        self.gist = params
        self.classes_ = classes
        self.mean_ = mean
        self.scale_ = scale
        self.coef_ = arrays["coef"]
        self.intercept_ = arrays["intercept"]
        self.calibration_a_ = arrays["calibration_a"]
        self.calibration_b_ = arrays["calibration_b"]
        self.rooms_ = _room_matrix(classes)

    def fit_folder(self, folder: str | os.PathLike[str]) -> EnvironmentModel:
        """Fit on a folder with one sub-folder of photographs per room category
        (``folder/office/*.jpg``, ``folder/kitchen/*.png``...).

        ``training_["cv_accuracy"]`` is then the stratified cross-validated accuracy, when
        every category has at least :data:`ACCURACY_MIN_PER_FOLD` images per fold of two
        or more folds (None otherwise, with the reason in ``training_["cv_note"]``).

        Raises
        ------
        ReadError
            The folder is missing or has no sub-folder; a sub-folder is not a room category
            or alias, holds no image or one image only; a file is not a readable image;
            fewer than two categories.
        """
        root = Path(folder)
        files, labels = _training_files(root)
        params = self.gist or GistParams()
        X = descriptors_of(files, params, description="GIST of training images")
        try:
            self.fit(X, labels)
        except InvalidParameterError as exc:  # pragma: no cover - checked per folder above
            raise ReadError(root, str(exc)) from None
        accuracy, note = cross_validated_accuracy(X, labels, C=self.C, seed=self.seed)
        self.training_.update(cv_accuracy=accuracy, cv_note=note, source=root.name)
        return self

    # -- prediction ---------------------------------------------------------------------
    def predict_proba(self, descriptors: ArrayLike) -> NDArray[np.float64]:
        """Calibrated probabilities ``(n, classes)`` of GIST descriptors ``(n, d)``.

        The mean over the calibration folds of each fold's one-vs-rest sigmoids,
        normalised to sum to 1 (the arithmetic of scikit-learn's
        ``CalibratedClassifierCV.predict_proba``, in NumPy).
        """
        self._check_fitted()
        X = np.asarray(descriptors, dtype=np.float64)
        if X.ndim == 1:
            X = X[None, :]
        d = self.mean_.shape[0]
        if X.ndim != 2 or X.shape[1] != d:
            raise InvalidParameterError("descriptors", f"an (n, {d}) array", f"shape {X.shape}")
        Z = (X - self.mean_) / self.scale_
        n_classes = len(self.classes_)
        total = np.zeros((len(Z), n_classes))
        for coef, intercept, a, b in zip(
            self.coef_, self.intercept_, self.calibration_a_, self.calibration_b_
        ):
            p = expit(-(a * (Z @ coef.T + intercept) + b))
            if n_classes == 2:
                proba = np.c_[1.0 - p[:, 0], p[:, 0]]
            else:
                s = p.sum(axis=1, keepdims=True)
                proba = np.divide(p, s, out=np.full_like(p, 1.0 / n_classes), where=s != 0)
            proba[(proba > 1.0) & (proba <= 1.0 + PROBABILITY_SLACK)] = 1.0
            total += proba
        return total / len(self.coef_)

    def room_probabilities(self, descriptors: ArrayLike) -> dict[str, float]:
        """P_N over room categories for one scene seen in ``(n, d)`` descriptors: the mean
        of the images' probabilities, aliases spread over their categories (``bedroom`` is
        half dorm room, half hotel room), sorted from most to least likely."""
        mean = self.predict_proba(descriptors).mean(axis=0)
        cats, matrix = self.rooms_
        p = mean @ matrix
        order = sorted(range(len(cats)), key=lambda k: (-p[k], cats[k]))
        return {cats[k]: float(p[k]) for k in order}

    # -- files --------------------------------------------------------------------------
    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the model as a ``.npz`` archive of arrays with a JSON header (no pickle)."""
        self._check_fitted()
        header = {
            "format": MODEL_FORMAT,
            "classes": list(self.classes_),
            "gist": self.gist.to_dict(),
            "classifier": {
                "kind": "linear SVM one-vs-rest, Platt sigmoid calibration",
                "C": float(self.C),
                "folds": int(self.coef_.shape[0]),
            },
            "training": _jsonable(self.training_),
            "ontodetect": __version__,
        }
        arrays = {
            "mean": self.mean_,
            "scale": self.scale_,
            "coef": self.coef_,
            "intercept": self.intercept_,
            "calibration_a": self.calibration_a_,
            "calibration_b": self.calibration_b_,
        }
        return write_array_archive(path, header, arrays)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> EnvironmentModel:
        """Read a model written by :meth:`save`; every number is checked, nothing unpickled.

        Raises
        ------
        ReadError
            Missing or unreadable file.
        CorruptFileError
            Not a model file, another format version, or arrays that disagree.
        """
        p = Path(path)
        header, arrays = read_array_archive(p, "model file")
        if header.get("format") != MODEL_FORMAT:
            raise CorruptFileError(p, f"format {header.get('format')!r}, expected {MODEL_FORMAT!r}")
        classes = header.get("classes")
        if (
            not isinstance(classes, list)
            or len(classes) < 2
            or not all(isinstance(c, str) and c for c in classes)
            or len(set(classes)) != len(classes)
        ):
            raise CorruptFileError(p, "'classes' is not a list of two or more distinct names")
        try:
            params = GistParams.from_dict(header.get("gist") or {})
            rooms = _room_matrix(tuple(classes))
        except (InvalidParameterError, TypeError) as exc:
            raise CorruptFileError(p, f"unusable header ({exc})") from None
        missing = [k for k in _ARRAYS if k not in arrays]
        if missing:
            raise CorruptFileError(p, f"missing arrays: {', '.join(missing)}")
        a = {k: np.asarray(arrays[k], dtype=np.float64) for k in _ARRAYS}
        d, k = params.length, (1 if len(classes) == 2 else len(classes))
        folds = a["coef"].shape[0] if a["coef"].ndim == 3 else 0
        shapes = {
            "mean": (d,),
            "scale": (d,),
            "coef": (folds, k, d),
            "intercept": (folds, k),
            "calibration_a": (folds, k),
            "calibration_b": (folds, k),
        }
        for name, shape in shapes.items():
            if a[name].shape != shape or folds < 1:
                raise CorruptFileError(
                    p, f"array {name!r} has shape {a[name].shape}, expected {shape}"
                )
            if not np.all(np.isfinite(a[name])):
                raise CorruptFileError(p, f"array {name!r} holds values that are not finite")
        if np.any(a["scale"] <= 0):
            raise CorruptFileError(p, "array 'scale' holds values that are not positive")
        classifier = header.get("classifier") if isinstance(header.get("classifier"), dict) else {}
        model = cls(C=_number(classifier.get("C"), 1.0), gist=params, seed=0)
        model.classes_ = tuple(classes)
        model.mean_, model.scale_ = a["mean"], a["scale"]
        model.coef_, model.intercept_ = a["coef"], a["intercept"]
        model.calibration_a_, model.calibration_b_ = a["calibration_a"], a["calibration_b"]
        model.rooms_ = rooms
        training = header.get("training")
        model.training_ = training if isinstance(training, dict) else {}
        return model

    def _check_fitted(self) -> None:
        if not hasattr(self, "coef_"):
            raise InvalidParameterError("model", "a fitted EnvironmentModel", "not fitted")

    def __repr__(self) -> str:
        if hasattr(self, "classes_"):
            return f"EnvironmentModel(classes={list(self.classes_)})"
        return f"EnvironmentModel(C={self.C}, seed={self.seed})"


# -- fitting with scikit-learn -----------------------------------------------------------
def _fit_calibrated(X: NDArray[np.float64], y: NDArray[np.intp], *, C: float, seed: int):
    """Standardise, then fit one-vs-rest linear SVMs with sigmoid calibration on held-out
    folds; returns (mean, scale, the fitted ``CalibratedClassifierCV``)."""
    from sklearn.calibration import CalibratedClassifierCV  # heavy: training only
    from sklearn.model_selection import StratifiedKFold
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import LinearSVC

    scaler = StandardScaler().fit(X)
    folds = min(CALIBRATION_FOLDS, int(np.bincount(y).min()))
    svm = LinearSVC(C=C, max_iter=SVM_MAX_ITER, random_state=seed)
    calibrated = CalibratedClassifierCV(
        svm,
        method="sigmoid",
        cv=StratifiedKFold(n_splits=folds, shuffle=True, random_state=seed),
        ensemble=True,
    )
    with warnings.catch_warnings():
        # Few images in many dimensions: the solver may stop at its iteration cap on a
        # fold that is already separated; the calibration absorbs the difference.
        warnings.filterwarnings("ignore", message=".*did not converge.*")
        calibrated.fit(scaler.transform(X), y)
    return scaler.mean_.astype(np.float64), scaler.scale_.astype(np.float64), calibrated


def _calibrated_arrays(calibrated, n_classes: int) -> dict[str, NDArray[np.float64]]:
    """The numbers prediction needs from a fitted ``CalibratedClassifierCV``."""
    coef, intercept, a, b = [], [], [], []
    for member in calibrated.calibrated_classifiers_:
        svm = member.estimator
        if list(svm.classes_) != list(range(n_classes)):  # pragma: no cover - stratified folds
            raise OntoDetectError("a calibration fold lacks a category; add images")
        coef.append(np.asarray(svm.coef_, dtype=np.float64))
        intercept.append(np.asarray(svm.intercept_, dtype=np.float64))
        a.append([float(c.a_) for c in member.calibrators])
        b.append([float(c.b_) for c in member.calibrators])
    return {
        "coef": np.stack(coef),
        "intercept": np.stack(intercept),
        "calibration_a": np.asarray(a, dtype=np.float64),
        "calibration_b": np.asarray(b, dtype=np.float64),
    }


def cross_validated_accuracy(
    descriptors: ArrayLike, labels: Sequence[str], *, C: float = 1.0, seed: int = 0
) -> tuple[float | None, str]:
    """Stratified k-fold accuracy of the whole model (calibration refitted in every fold),
    with ``k = min(5, smallest class // 2)`` so that each held-out fold has at least two
    images of every class; (None, reason) when that leaves fewer than two folds."""
    X = np.asarray(descriptors, dtype=np.float64)
    names = np.asarray([_class_name(v) for v in labels])
    _, y = np.unique(names, return_inverse=True)
    smallest = int(np.bincount(y).min())
    k = min(ACCURACY_FOLDS, smallest // ACCURACY_MIN_PER_FOLD)
    if k < 2:
        need = 2 * ACCURACY_MIN_PER_FOLD
        return None, (
            f"not estimated: the smallest category has {smallest} images, "
            f"{need} are needed for two folds of {ACCURACY_MIN_PER_FOLD} each"
        )
    from sklearn.model_selection import StratifiedKFold  # heavy: training only

    hits = 0
    splits = StratifiedKFold(n_splits=k, shuffle=True, random_state=seed).split(X, y)
    for train, test in splits:
        model = EnvironmentModel(C=C, seed=seed).fit(X[train], list(names[train]))
        predicted = np.asarray(model.classes_)[model.predict_proba(X[test]).argmax(axis=1)]
        hits += int(np.sum(predicted == names[test]))
    return hits / len(X), f"{k}-fold stratified cross-validation"


# -- files and folders -------------------------------------------------------------------
def _training_files(root: Path) -> tuple[list[Path], list[str]]:
    """Images and their room names from ``root/<room>/<image>``, checked folder by folder."""
    if not root.exists():
        raise ReadError(root, "no such folder of training images")
    if not root.is_dir():
        raise ReadError(root, "not a folder - expected one sub-folder of images per category")
    try:
        subs = sorted(e for e in root.iterdir() if e.is_dir() and not e.name.startswith("."))
    except OSError as exc:
        raise ReadError(root, f"cannot list the folder ({exc.strerror or exc})") from None
    if not subs:
        raise ReadError(root, "holds no sub-folder - expected one folder of images per category")
    files: list[Path] = []
    labels: list[str] = []
    seen: dict[str, Path] = {}
    for sub in subs:
        try:
            key = _class_name(sub.name)
        except InvalidParameterError as exc:
            raise ReadError(sub, f"not a room category or alias ({exc.rule})") from None
        if key in seen:
            raise ReadError(sub, f"the same category as {seen[key]}")
        seen[key] = sub
        images = image_files(sub)
        if len(images) < MIN_IMAGES_PER_CATEGORY:
            raise ReadError(
                sub,
                f"{len(images)} image; each category needs at least "
                f"{MIN_IMAGES_PER_CATEGORY} (one to fit, one to calibrate)",
            )
        files += images
        labels += [key] * len(images)
    if len(seen) < 2:
        only = next(iter(seen))
        raise ReadError(
            root,
            f"one category only ({only}) - a classifier needs at least two to tell apart",
        )
    return files, labels


def descriptors_of(
    images: Sequence[str | os.PathLike[str] | ArrayLike],
    params: GistParams | None = None,
    *,
    description: str = "GIST",
) -> NDArray[np.float64]:
    """GIST descriptors ``(n, d)`` of image files or arrays, with a progress bar."""
    params = params or GistParams()
    out = np.empty((len(images), params.length))
    with progress(description, total=len(images)) as advance:
        for i, image in enumerate(images):
            if isinstance(image, (str, os.PathLike)):
                out[i] = gist(read_image(image), params)
            else:
                out[i] = gist(image, params)
            advance(1)
    return out


def _scene_images(images: Any) -> list[Any]:
    """A path (file or folder), an array, or a sequence of them -> a list of images."""
    if isinstance(images, (str, os.PathLike)):
        return list(image_files(images))
    if isinstance(images, np.ndarray):
        return [images]
    found: list[Any] = []
    for item in images:
        found += _scene_images(item) if isinstance(item, (str, os.PathLike)) else [item]
    if not found:
        raise InvalidParameterError("images", "at least one image", "none")
    return found


def train_environment(
    folder: str | os.PathLike[str],
    *,
    C: float = 1.0,
    gist: GistParams | None = None,
    seed: int = 0,
) -> EnvironmentModel:
    """Train a scene classifier on ``folder/<room category>/<images>``.

    See :meth:`EnvironmentModel.fit_folder`; sub-folder names are categories or aliases
    that :func:`ontodetect.ontology.room_distribution` accepts (``office``,
    ``living_room``, ``conference``...).
    """
    return EnvironmentModel(C=C, gist=gist, seed=seed).fit_folder(folder)


def predict_environment(
    images: Any, model: EnvironmentModel | str | os.PathLike[str]
) -> dict[str, float]:
    """P_N over room categories from photographs of one scene.

    Parameters
    ----------
    images : path, array or sequence of them
        An image file, a folder of images (all of them), an ``(h, w)`` or ``(h, w, c)``
        array, or a list of any of these. Their probabilities are averaged, as the thesis
        averages the frames of a scene (Tables 4.11–4.13).
    model : EnvironmentModel or path
        A fitted model or a model file written by :meth:`EnvironmentModel.save`.

    Returns
    -------
    dict
        Category -> probability, summing to 1, most likely first.
    """
    if not isinstance(model, EnvironmentModel):
        model = EnvironmentModel.load(model)
    model._check_fitted()
    found = _scene_images(images)
    X = descriptors_of(found, model.gist, description="GIST of scene images")
    return model.room_probabilities(X)


def _room_matrix(classes: tuple[str, ...]) -> tuple[list[str], NDArray[np.float64]]:
    """The categories the classes stand for and the ``(classes, categories)`` matrix of
    each class's distribution over them (one 1 for a category, a row of shares for an
    alias such as ``bedroom``)."""
    dists = [room_distribution(c) or {} for c in classes]
    cats = sorted({k for d in dists for k in d})
    matrix = np.array([[d.get(k, 0.0) for k in cats] for d in dists], dtype=np.float64)
    return cats, matrix


def _number(value: Any, default: float) -> float:
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    return default


def _jsonable(data: Mapping[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in data.items():
        if isinstance(v, Mapping):
            out[str(k)] = _jsonable(v)
        elif isinstance(v, (np.integer, np.floating)):
            out[str(k)] = v.item()
        else:
            out[str(k)] = v
    return out
