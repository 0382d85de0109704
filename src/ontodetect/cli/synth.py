"""``ontodetect synth``: simulated rooms scanned by virtual sensors, with ground truth."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import typer
import yaml
from rich.text import Text

from ..errors import InvalidParameterError
from ..io._yaml import load_yaml
from . import app
from ._console import console, reporting, state
from ._defaults import SENSORS

_SENSOR_HELP = {
    "rgbd": "Kinect-like RGB-D camera walked around the room, frames fused (world frame)",
    "rgbd-frame": "one organized RGB-D frame (camera frame; also written as frame.pcd)",
    "tls": "terrestrial laser scanner at a few tripod stations, with intensity",
    "monocular": "semi-dense monocular SLAM map at an unknown scale, with odometry distance",
}


def _parse_options(items: list[str]) -> dict[str, Any]:
    options: dict[str, Any] = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or not name.strip():
            raise InvalidParameterError("option", "NAME=VALUE (e.g. stride=2)", item)
        try:
            value = load_yaml(text)
        except yaml.YAMLError:
            value = text
        options[name.strip()] = tuple(value) if isinstance(value, list) else value
    return options


@app.command()
def synth(
    out: Path | None = typer.Option(
        None, "--out", "-o", help="Output folder (with --count: one sub-folder per scene)."
    ),
    room: str = typer.Option(
        "office",
        "--room",
        "-r",
        help="Room type, or several separated by commas to cycle through with --count "
        "(see --list).",
    ),
    sensor: str = typer.Option("rgbd", "--sensor", "-s", help=f"One of {', '.join(SENSORS)}."),
    seed: int = typer.Option(0, "--seed", help="Seed of the first scene (scene i uses seed+i)."),
    count: int = typer.Option(
        1, "--count", "-n", help="Number of scenes; more than 1 writes OUT/scene_0000, ..."
    ),
    points: int | None = typer.Option(
        None, "--points", "-p", help="Approximate number of points per scene."
    ),
    clutter: float = typer.Option(1.0, "--clutter", help="More (>1) or fewer (<1) small objects."),
    object_meshes: bool = typer.Option(
        False, "--object-meshes", help="Also write objects/<id>.ply, one mesh per object."
    ),
    option: list[str] = typer.Option(
        [],
        "--option",
        "-O",
        metavar="NAME=VALUE",
        help="Sensor option, e.g. -O stride=2 -O drift=0.01 -O 'noise=[0.001, 0.002]'.",
    ),
    furnished: bool = typer.Option(
        False,
        "--furnished",
        help="Furnish the room with Sweet Home 3D catalogue models instead of parametric "
        "furniture (room types: see --list --furnished).",
    ),
    catalog: Path | None = typer.Option(
        None,
        "--catalog",
        help="Folder of Sweet Home 3D catalogues (*.sh3f) for --furnished (implies it); "
        "default $ONTODETECT_SH3D_DIR or /usr/share/sweethome3d/furniture.",
    ),
    list_: bool = typer.Option(False, "--list", help="List room types and sensors, then exit."),
) -> None:
    """Simulate scans of furnished rooms with per-point ground truth (cloud.ply, objects.json,
    scene.json, mesh.ply)."""
    from ..synth import (  # lazy: CLI start-up
        room_types,
        sensor_options,
        synthesize,
        synthesize_many,
        write_synth,
    )
    from ..synth.furnished import FURNISHED_ROOM_TYPES  # lazy: CLI start-up

    furnished = furnished or catalog is not None
    if list_:
        kinds = FURNISHED_ROOM_TYPES if furnished else room_types()
        console.print(Text.assemble(("room types", "bold"), ": " + ", ".join(kinds)))
        console.print(Text.assemble(("sensors", "bold"), ":"))
        for name in SENSORS:
            console.print(f"  {name:<11} {_SENSOR_HELP[name]}")
            console.print(f"  {'':<11} options: {', '.join(sensor_options(name))}", style="dim")
        return
    if out is None:
        raise InvalidParameterError("out", "a folder given with -o/--out", None)
    rooms = [r.strip() for r in room.split(",") if r.strip()]
    options = _parse_options(option)
    if furnished:
        _synth_furnished(rooms, sensor, seed, count, out, points, catalog, object_meshes, options)
        return
    if count == 1 and len(rooms) == 1:
        with reporting():
            result = synthesize(rooms[0], sensor, seed, points=points, clutter=clutter, **options)
            folder = write_synth(result, out, object_meshes=object_meshes)
        _show_scene(folder, result)
        return

    def show(i: int, result: Any, folder: Path) -> None:
        _show_scene(folder, result)

    with reporting():
        synthesize_many(
            count,
            rooms,
            sensor,
            seed,
            out_dir=out,
            points=points,
            clutter=clutter,
            object_meshes=object_meshes,
            on_scene=show,
            **options,
        )


def _synth_furnished(
    rooms: list[str],
    sensor: str,
    seed: int,
    count: int,
    out: Path,
    points: int | None,
    catalog: Path | None,
    object_meshes: bool,
    options: dict[str, Any],
) -> None:
    """Furnished rooms: one scene in OUT, or OUT/scene_0000... with --count."""
    from ..synth import write_synth  # lazy: CLI start-up
    from ..synth.furnished import (  # lazy: CLI start-up
        FURNISHED_ROOM_TYPES,
        synthesize_furnished,
    )

    for name in rooms:
        if name not in FURNISHED_ROOM_TYPES:
            raise InvalidParameterError("room", f"one of {', '.join(FURNISHED_ROOM_TYPES)}", name)
    if count < 1:
        raise InvalidParameterError("count", "a positive integer", count)
    with reporting():
        for i in range(count):
            result = synthesize_furnished(
                rooms[i % len(rooms)],
                sensor,
                seed + i,
                catalog_dir=catalog,
                points=points,
                **options,
            )
            folder = out if count == 1 else out / f"scene_{i:04d}"
            write_synth(result, folder, object_meshes=object_meshes)
            _show_scene(folder, result)


def _show_scene(folder: Path, result: Any) -> None:
    """One line per scene written: its folder and what it holds (none with --quiet)."""
    if not state.quiet:
        console.print(f"{folder}: {result.summary()}", markup=False, soft_wrap=True)
