"""Options several commands share: configuration, overrides, ontology, room."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from ..errors import InvalidParameterError, ReadError
from ..io._textfile import read_text
from ..io._yaml import describe_yaml_error, load_yaml

if TYPE_CHECKING:
    from ..config import Config
    from ..ontology import Ontology


#: Options that set one configuration key: option name -> dotted key.
CONFIG_OPTIONS = {
    "up": "prepare.up",
    "scale": "prepare.scale",
    "threshold": "detect.threshold",
    "beta": "detect.beta",
    "context": "detect.context",
    "votes": "detect.votes",
    "proposals": "detect.proposals",
    "classes": "detect.classes",
}


def load_config(config: Path | None, overrides: list[str], **options: Any) -> Config:
    """The configuration from ``--config`` (or the defaults) with ``--set`` overrides, then
    the options that set one key (:data:`CONFIG_OPTIONS`; None: not given), checked by the
    key's own rule."""
    from ..config import Config  # lazy: CLI start-up (info needs no configuration)

    cfg = Config.from_yaml(config) if config is not None else Config()
    cfg = cfg.with_overrides(overrides) if overrides else cfg
    changes: dict[str, dict[str, Any]] = {}
    for name, value in options.items():
        if value is not None:
            section, key = CONFIG_OPTIONS[name].split(".")
            changes.setdefault(section, {})[key] = value
    return cfg.replace(**changes) if changes else cfg


def check_up_option(up: str | None) -> None:
    """``--up`` is one of :data:`~ontodetect.config.UP_CHOICES` (None: not given); checked
    before the configuration is loaded, so that the error names the option, not the key it
    sets (``prepare.up``)."""
    from ..config import UP_CHOICES, OneOf, check_param  # lazy: CLI start-up

    if up is not None:
        check_param("--up", OneOf(UP_CHOICES), up)


def load_ontology_option(files: list[Path], only: bool) -> Ontology:
    """The built-in ontology with ``--ontology`` files merged in (or only them)."""
    from ..ontology import load_ontology  # lazy: CLI start-up

    if only and not files:
        raise InvalidParameterError(
            "--ontology-only", "used with at least one --ontology FILE", "no file"
        )
    return load_ontology(*files, replace=only)


def room_option(room: str | None, room_probs: Path | None) -> str | dict[str, Any] | None:
    """``--room NAME`` or ``--room-probs FILE`` (a YAML/JSON mapping category -> weight);
    ``auto`` (estimated from the scan) when neither is given, None for ``--room none``."""
    if room is not None and room_probs is not None:
        raise InvalidParameterError("--room-probs", "not combined with --room", str(room_probs))
    if room_probs is None:
        if room is None:
            return "auto"
        return None if room.strip().lower() == "none" else room
    text = read_text(room_probs, "room probability file")
    try:
        data = load_yaml(text)
    except yaml.YAMLError as exc:
        raise ReadError(
            room_probs, f"not a readable YAML/JSON mapping{describe_yaml_error(exc)}"
        ) from None
    if not isinstance(data, dict):
        raise ReadError(room_probs, "expected a mapping of room category to probability")
    return data


def number_list(text: str | None, kind: type, option: str) -> list | None:
    """``"0,90,180"`` -> ``[0.0, 90.0, 180.0]`` (None when the option was not given)."""
    if text is None:
        return None
    try:
        return [kind(v) for v in text.split(",") if v.strip()]
    except ValueError:
        what = "integers" if kind is int else "numbers"
        raise InvalidParameterError(option, f"a comma-separated list of {what}", text) from None


#: Help of the options that choose where batch work runs (shared by detect, eval, calibrate).
SCHEDULER_HELP = (
    "Run on the Dask cluster whose scheduler is at tcp://HOST:PORT (default: "
    "$DASK_SCHEDULER_ADDRESS when set); every worker must see the input at the same path."
)
WORKERS_HELP = "Run on a local Dask cluster of N worker processes (one thread each)."


#: The commands' names of the executor's parameters, for their errors.
EXECUTOR_OPTIONS = {"scheduler": "--scheduler", "workers": "--workers", "jobs": "--jobs"}


def check_executor_options(scheduler: str | None, workers: int | None, jobs: int | None) -> None:
    """Before any work: ``--scheduler``, ``--workers`` and ``--jobs`` are well formed,
    whether or not the run needs an executor (one scan uses none); errors name the option."""
    from .._executor import scheduler_address  # lazy: CLI start-up
    from ..config import COUNT, Nullable, check_param  # lazy: CLI start-up

    if scheduler is not None and workers is not None:
        raise InvalidParameterError("--workers", "not combined with --scheduler", workers)
    with _executor_option_names():
        scheduler_address(scheduler)
        check_param("workers", Nullable(COUNT), workers)
        check_param("jobs", Nullable(COUNT), jobs)


def refuse_executor_options(scheduler: str | None, workers: int | None, jobs: int) -> None:
    """One scan without ``--tile`` runs in this process: ``--scheduler``, ``--workers`` or
    ``--jobs`` other than 1 would be left unused, so the first given is an error."""
    given = {"scheduler": scheduler, "workers": workers, "jobs": None if jobs == 1 else jobs}
    for name, value in given.items():
        if value is not None:
            raise InvalidParameterError(
                EXECUTOR_OPTIONS[name],
                "given only with several scans or --tile (one scan runs in this process)",
                value,
            )


def executor_option(scheduler: str | None, workers: int | None, jobs: int | None = None) -> Any:
    """The executor ``--scheduler``, ``--workers`` or ``--jobs`` ask for (an open one: use
    it in a ``with`` block); errors name the option."""
    from .._executor import open_executor  # lazy: CLI start-up (Dask loads when asked for)

    check_executor_options(scheduler, workers, jobs)
    with _executor_option_names():
        return open_executor(scheduler, workers=workers, jobs=jobs)


@contextlib.contextmanager
def _executor_option_names() -> Iterator[None]:
    """The executor's parameter errors, named by the commands' options."""
    try:
        yield
    except InvalidParameterError as exc:
        option = EXECUTOR_OPTIONS.get(exc.name)
        if option is None:
            raise
        raise InvalidParameterError(option, exc.rule, exc.value) from None
