"""``ontodetect env train IMAGES_DIR -o MODEL`` and ``ontodetect env predict IMAGE --model
MODEL``: the room prior P_N from photographs; and the ``--scene-image``/``--env-model``
options of ``detect``."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import typer
from rich.table import Table

from ..errors import InvalidParameterError
from . import app
from ._console import console, reporting, state

env_app = typer.Typer(
    name="env",
    help="The room prior P_N from photographs: train a scene classifier (GIST and a "
    "calibrated SVM), predict P_N for a scene.",
    no_args_is_help=True,
    context_settings={"help_option_names": ["-h", "--help"]},
)
app.add_typer(env_app, name="env")


@env_app.command("train")
def train(
    images: Path = typer.Argument(
        ...,
        metavar="IMAGES_DIR",
        help="A folder with one sub-folder of images per room category "
        "(office/, living_room/, conference/...: Places205 categories or aliases).",
    ),
    out: Path = typer.Option(..., "--out", "-o", help="Model file to write (.npz)."),
    c: float = typer.Option(1.0, "--C", help="Inverse regularisation of the linear SVMs."),
    seed: int = typer.Option(0, "--seed", help="Seed of the calibration folds."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
) -> None:
    """Train a scene classifier on photographs; write it as a model file (no pickle)."""
    from ..environment import train_environment  # lazy: CLI start-up (scikit-learn, Pillow)

    with reporting():
        model = train_environment(images, C=c, seed=seed)
        written = model.save(out)
    summary = {
        "model": str(written),
        "classes": list(model.classes_),
        "images": model.training_["images"],
        "cv_accuracy": model.training_["cv_accuracy"],
        "cv_note": model.training_["cv_note"],
    }
    if as_json:
        typer.echo(json.dumps(summary))
        return
    if state.quiet:
        return
    table = Table(title=f"{images}: {sum(summary['images'].values())} images")
    table.add_column("category")
    table.add_column("images", justify="right")
    for name, count in summary["images"].items():
        table.add_row(name, str(count))
    console.print(table)
    if summary["cv_accuracy"] is None:
        console.print(f"cross-validated accuracy {summary['cv_note']}")
    else:
        console.print(
            f"cross-validated accuracy {summary['cv_accuracy']:.1%} ({summary['cv_note']})"
        )
    console.print(f"wrote {written}")


@env_app.command("predict")
def predict(
    image: Path = typer.Argument(
        ...,
        metavar="IMAGE",
        help="A photograph of the scene, or a folder of them (their P_N is averaged).",
    ),
    model: Path = typer.Option(..., "--model", "-m", help="Model file from 'env train'."),
    as_json: bool = typer.Option(False, "--json", help="Print P_N as JSON."),
) -> None:
    """Print P_N, the probability of each room category, as Tables 4.11–4.13 do."""
    from ..environment import EnvironmentModel, predict_environment  # lazy: CLI start-up
    from ..io import image_files  # lazy: CLI start-up

    files = image_files(image)
    with reporting():
        rooms = predict_environment(files, EnvironmentModel.load(model))
    if as_json:
        typer.echo(json.dumps({"images": [str(p) for p in files], "rooms": rooms}))
        return
    if state.quiet:
        return
    count = f"{len(files)} image" + ("s" if len(files) != 1 else "")
    table = Table(title=f"{image}: P_N from {count}")
    table.add_column("category")
    table.add_column("P_N", justify="right")
    for name, p in rooms.items():
        table.add_row(name, f"{p:.1%}")
    console.print(table)


def scene_image_room(
    scene_image: Path | None,
    env_model: Path | None,
    room: str | None,
    room_probs: Path | None,
) -> dict[str, float] | None:
    """``detect --scene-image IMAGE_OR_DIR --env-model MODEL``: P_N from the photographs
    (None when neither option is given). With ``--room auto`` (the default) it is combined
    with the scan's own estimate; with ``--room none`` it is the prior alone, as
    ``--room-probs`` would be."""
    if scene_image is None and env_model is None:
        return None
    if scene_image is None or env_model is None:
        given, missing = (
            ("--scene-image", "--env-model")
            if env_model is None
            else ("--env-model", "--scene-image")
        )
        raise InvalidParameterError(given, f"given with {missing}", "without it")
    named = room is not None and room.strip().lower() not in ("auto", "none")
    if named or room_probs is not None:
        other = "--room" if named else "--room-probs"
        raise InvalidParameterError(
            "--scene-image",
            f"not combined with {other} (both set the room prior)",
            str(scene_image),
        )
    from ..environment import predict_environment  # lazy: CLI start-up (Pillow)

    with reporting():
        rooms: dict[str, Any] = predict_environment(scene_image, env_model)
    if state.verbose:
        top = ", ".join(f"{k} {v:.1%}" for k, v in list(rooms.items())[:3])
        console.print(f"room prior from {scene_image}: {top}")
    return rooms
