"""One entry point for every benchmark: ``python -m benchmarks NAME [options]``.

``NAME`` is the part after ``bench_`` of a script in this folder (``io``,
``geometry``, ``pipeline``, ``synth``, ``detect`` ...); the options go to that
script (``python -m benchmarks pipeline --help``). ``all`` runs :data:`ALL` one
after the other with their defaults (long: they go up to 10 million points).
``python -m benchmarks`` alone lists the benchmarks.

Examples::

    python -m benchmarks io --points 1000000
    python -m benchmarks pipeline --sizes 100000 1000000 --cache /tmp/scans
    python -m benchmarks all
"""

from __future__ import annotations

import importlib
import inspect
import pkgutil
import sys
from collections.abc import Sequence
from pathlib import Path

#: What ``all`` runs, in this order (those that need no dataset argument).
ALL = ("io", "geometry", "pipeline")
PREFIX = "bench_"


def available() -> dict[str, str]:
    """Benchmark name -> first line of its docstring."""
    out = {}
    for info in sorted(pkgutil.iter_modules([str(Path(__file__).parent)]), key=lambda m: m.name):
        if info.name.startswith(PREFIX):
            name = info.name[len(PREFIX) :]
            module = importlib.import_module(f"{__package__}.{info.name}")
            out[name] = (module.__doc__ or "").strip().splitlines()[0] if module.__doc__ else ""
    return out


def run(name: str, argv: Sequence[str]) -> int:
    """Run one benchmark's ``main`` with ``argv`` (scripts that read ``sys.argv`` get it there)."""
    module = importlib.import_module(f"{__package__}.{PREFIX}{name}")
    main = module.main
    saved = sys.argv
    # Scripts that parse sys.argv get the options there; the others as an argument.
    sys.argv = [f"python -m {__package__} {name}", *argv]
    try:
        status = main(list(argv)) if inspect.signature(main).parameters else main()
    finally:
        sys.argv = saved
    return int(status or 0)


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    names = available()
    if not args or args[0] in ("-h", "--help"):
        print(__doc__.strip().splitlines()[0] + "\n")
        width = max(map(len, names)) if names else 0
        for name, doc in names.items():
            print(f"  {name:<{width}}  {doc}")
        print(f"  {'all':<{width}}  {', '.join(ALL)} in turn, with their defaults")
        return 0
    name, rest = args[0], args[1:]
    if name == "all":
        if rest:
            print(
                "'all' takes no options; run the benchmarks one by one to pass some",
                file=sys.stderr,
            )
            return 2
        status = 0
        for one in ALL:
            print(f"\n## {one}\n", flush=True)
            status = max(status, run(one, []))
        return status
    if name not in names:
        print(
            f"unknown benchmark {name!r}; choose from: {', '.join([*names, 'all'])}",
            file=sys.stderr,
        )
        return 2
    return run(name, rest)


if __name__ == "__main__":
    sys.exit(main())
