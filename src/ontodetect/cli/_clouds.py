"""The one cloud or scan a command reads: the names ``--format`` takes."""

from __future__ import annotations

from ..errors import InvalidParameterError
from ..io import supported_formats
from ..io._layouts import DATASET_FORMATS, FORMAT_ALIASES

#: Help of ``--format`` for the commands that read one cloud per input.
FORMAT_HELP = (
    f"Force the input format: {', '.join(supported_formats())} (sunrgbd and votenet name "
    "the VoteNet layouts)."
)


def cloud_format(format: str | None, command: str) -> str | None:
    """The reader ``--format`` names: one of :func:`~ontodetect.io.supported_formats`, or
    a layout's other name in ``eval -f`` (``sunrgbd``, ``votenet``) when it names one;
    errors name ``--format`` and say what ``command`` reads.

    Examples
    --------
    >>> cloud_format("sunrgbd", "info"), cloud_format("PLY", "info"), cloud_format(None, "info")
    ('sunrgbd-votenet', 'ply', None)
    """
    if format is None:
        return None
    name = format.strip().lower()
    name = FORMAT_ALIASES.get(name, name)
    readable = supported_formats()
    if name in readable:
        return name
    rule = "one of " + ", ".join(readable) + f" ({command} reads one cloud or scan)"
    if name in DATASET_FORMATS:
        rule += f"; {format!r} is a dataset layout: 'ontodetect eval -f {format}' reads it"
    raise InvalidParameterError("--format", rule, format)
