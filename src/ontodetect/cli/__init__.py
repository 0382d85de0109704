"""Command-line interface: ``ontodetect COMMAND ...``.

Each command is a thin layer over a public function of the library; this
package only parses arguments, shows progress and prints results. Any
:class:`~ontodetect.errors.OntoDetectError` becomes one line on stderr and exit
status 2.
"""

from __future__ import annotations

import os
import sys
import traceback
import warnings

import typer
from rich.text import Text

from .._version import __version__
from ..errors import OntoDetectError
from ._console import err_console, setup_output, state

__all__ = ["app", "main"]

app = typer.Typer(
    name="ontodetect",
    help="Find furniture in 3D point clouds of indoor scenes with probabilistic ontological "
    "priors: no training data, a CPU, and rules you can read and edit.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _show_version(value: bool) -> None:
    if value:
        typer.echo(f"ontodetect {__version__}")
        raise typer.Exit()


@app.callback()
def _global_options(
    quiet: bool = typer.Option(
        False,
        "--quiet",
        "-q",
        help="No progress bars, tables or summaries (the files are written all the same); "
        "errors, warnings and what info, cad models, --json and --explain print still appear.",
    ),
    verbose: bool = typer.Option(False, "--verbose", "-v", help="Print more detail."),
    version: bool = typer.Option(
        False,
        "--version",
        callback=_show_version,
        is_eager=True,
        help="Print the version and exit.",
    ),
) -> None:
    setup_output(quiet=quiet, verbose=verbose)


# Importing a command module registers its command(s) on ``app``. The command modules
# import the library's stages inside the commands, so that building the CLI (--help,
# --version) imports none of them.
from . import cad, calibrate, demo, detect, env, evaluate, info, segment, synth, view  # noqa: E402, F401

#: Global options that may also be given after the command (``detect ... -q``).
GLOBAL_FLAGS = frozenset({"-q", "--quiet", "-v", "--verbose"})


def hoist_global_options(argv: list[str]) -> list[str]:
    """Move the global flags given after the command in front of it (up to ``--``).

    Examples
    --------
    >>> hoist_global_options(["detect", "a.ply", "-q", "-o", "out"])
    ['-q', 'detect', 'a.ply', '-o', 'out']
    >>> hoist_global_options(["detect", "--", "-q"])
    ['detect', '--', '-q']
    """
    end = argv.index("--") if "--" in argv else len(argv)
    flags = [a for a in argv[:end] if a in GLOBAL_FLAGS]
    rest = [a for a in argv[:end] if a not in GLOBAL_FLAGS]
    return [*flags, *rest, *argv[end:]]


#: Options whose value may be left out, and the value they then take (``--explain`` alone
#: explains every class; ``--explain chair,table`` those).
OPTIONAL_VALUES = {"--explain": "all"}


def fill_optional_values(argv: list[str]) -> list[str]:
    """Give the options of :data:`OPTIONAL_VALUES` their default when no value follows.

    A following token is the option's value unless it starts with ``-`` or looks like a
    path (holds ``/`` or ``.``); class lists never do.

    Examples
    --------
    >>> fill_optional_values(["detect", "a.ply", "--explain", "-o", "out"])
    ['detect', 'a.ply', '--explain', 'all', '-o', 'out']
    >>> fill_optional_values(["detect", "--explain", "chair,table", "a.ply"])
    ['detect', '--explain', 'chair,table', 'a.ply']
    >>> fill_optional_values(["detect", "--explain", "a.ply"])
    ['detect', '--explain', 'all', 'a.ply']
    """
    out: list[str] = []
    for k, arg in enumerate(argv):
        out.append(arg)
        if arg == "--":
            return out + argv[k + 1 :]
        if arg in OPTIONAL_VALUES:
            nxt = argv[k + 1] if k + 1 < len(argv) else None
            if nxt is None or nxt.startswith("-") or "/" in nxt or "." in nxt:
                out.append(OPTIONAL_VALUES[arg])
    return out


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit status instead of raising ``SystemExit``.

    Global options (``-q``, ``-v``) are accepted before or after the command.
    """
    argv = fill_optional_values(hoist_global_options(list(sys.argv[1:] if argv is None else argv)))

    def _show_warning(message, category, filename, lineno, file=None, line=None):
        _say("warning", "yellow", str(message))

    old_show = warnings.showwarning
    warnings.showwarning = _show_warning
    try:
        # Outside standalone mode Click returns a command's typer.Exit code instead of
        # raising it: a batch with a failed scan exits with it.
        code = app(args=argv, prog_name="ontodetect", standalone_mode=False)
        if isinstance(code, int) and code:
            return code
    except OntoDetectError as exc:
        _fail(str(exc), exc)
        return 2
    except typer.Exit as exc:
        return int(exc.exit_code or 0)
    except typer.Abort:
        _say("aborted", "red", "")
        return 130
    except KeyboardInterrupt:
        _say("interrupted", "red", "")
        return 130
    except MemoryError as exc:
        _fail(f"{_inputs(argv)}out of memory: the input is larger than this machine can hold", exc)
        return 2
    except RecursionError as exc:
        _fail(f"{_inputs(argv)}an input is nested too deeply to be read", exc)
        return 2
    except OSError as exc:
        _fail(_os_message(exc), exc)
        return 2
    except Exception as exc:  # usage errors from the argument parser, then anything else
        show = getattr(exc, "show", None)
        code = getattr(exc, "exit_code", None)
        if callable(show) and isinstance(code, int):
            show(file=sys.stderr)
            return code
        _fail(f"{_inputs(argv)}unexpected {type(exc).__name__}: {exc} (a bug; -v shows where)", exc)
        return 2
    finally:
        warnings.showwarning = old_show
    return 0


def _say(kind: str, colour: str, message: str) -> None:
    """One line on stderr: a coloured tag, then ``message`` verbatim (never read as markup)."""
    line = Text(f"{kind}: " if message else kind, style=colour)
    # One line whatever the message holds (a library's multi-line text, a file's newlines).
    line.append(" ".join(part.strip() for part in message.splitlines()))
    err_console.print(line, highlight=False, soft_wrap=True)


def _fail(message: str, exc: BaseException) -> None:
    _say("error", "red", message)
    if state.verbose and not isinstance(exc, OntoDetectError):
        err_console.print(
            Text("".join(traceback.format_exception(exc))), highlight=False, soft_wrap=True
        )


def _inputs(argv: list[str] | None) -> str:
    """``"while reading a.ply, o.yaml: "``: the files named on the command line, for an
    error that does not say which one it came from."""
    args = sys.argv[1:] if argv is None else argv
    files = [a for a in args if not a.startswith("-") and os.path.isfile(a)]
    return f"while reading {', '.join(files)}: " if files else ""


def _os_message(exc: OSError) -> str:
    """``path: problem`` from an OSError that escaped the readers and writers."""
    what = exc.strerror or str(exc) or type(exc).__name__
    if exc.filename is not None:
        return f"{exc.filename}: {what}"
    return what


def _entry() -> None:  # pragma: no cover - console script
    sys.exit(main())
