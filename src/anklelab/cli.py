"""The ``anklelab`` command. Each command group lives in its own module under ``commands``."""

from __future__ import annotations

import errno
import functools
import os
import signal
import sys
import threading
from typing import Annotated, Any

import typer

from anklelab import __version__
from anklelab.commands import (
    analyze,
    batch,
    capstan,
    demo,
    design,
    forceplate,
    identify,
    imports,
    platform,
    report,
    session,
    simulate,
    study,
    tree,
)
from anklelab.errors import AnklelabError

app = typer.Typer(
    help="anklelab: digital twins, control and identification for ankle actuation platforms.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
    rich_markup_mode=None,
)
app.add_typer(platform.app, name="platform")
app.add_typer(session.app, name="session")
app.add_typer(imports.app, name="import")
app.command("analyze")(analyze.analyze)
app.command("forceplate")(forceplate.forceplate)
app.command("inspect")(tree.inspect)
app.add_typer(identify.app, name="identify")
app.add_typer(simulate.app, name="simulate")
app.add_typer(capstan.app, name="capstan")
app.command("demo")(demo.demo)
app.command("report")(report.report)
app.command("study")(study.study)
app.command("design")(design.design)
app.command("batch")(batch.batch)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"anklelab {__version__}")
        raise typer.Exit()


@app.callback()
def main(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Show the version.")
    ] = False,
) -> None:
    """anklelab: digital twins, control and identification for ankle actuation platforms."""


_SIGNALS = (signal.SIGINT, signal.SIGTERM)


def _interrupt(signum: int, frame: object) -> None:
    """SIGINT or SIGTERM: unwind the command so that its temporaries are removed; noted too,
    so that no output is committed if the exception is swallowed (see :mod:`anklelab._atomic`)."""
    from anklelab._atomic import Interrupted, note_interrupt

    for number in _SIGNALS:  # a second signal must not cut the clean-up short
        signal.signal(number, signal.SIG_IGN)
    note_interrupt(signum)
    raise Interrupted(signum)


def _unraisable(hook: Any) -> Any:
    """``sys.unraisablehook`` that keeps quiet about :class:`~anklelab._atomic.Interrupted`: a
    signal handled inside a finaliser cannot unwind from there, and Python would print a
    traceback; the interruption is noted and stops the next commit instead."""
    from anklelab._atomic import Interrupted

    def quiet(unraisable: Any) -> None:
        if not isinstance(unraisable.exc_value, Interrupted):
            hook(unraisable)

    return quiet


def _os_error(exc: OSError) -> str:
    """One line for an operating-system error: the path the user named, and what happened."""
    from anklelab._atomic import untemporary

    reason = untemporary(" ".join((exc.strerror or str(exc)).split()))
    where = f"{untemporary(str(exc.filename))}: " if exc.filename else ""
    hint = {
        errno.ENOSPC: "; nothing was written, free some space",
        errno.EDQUOT: "; nothing was written, free some space",
        errno.EROFS: "; write somewhere else",
        errno.EACCES: "; check the permissions or write somewhere else",
    }.get(exc.errno or 0, "")
    return f"{where}{reason}{hint}"


@functools.cache
def _command() -> Any:
    """The click command of ``app``, built once per process (typer builds it on every call)."""
    return typer.main.get_command(app)


def _click_error() -> type[Exception]:
    """click's base exception (recent typer versions vendor click)."""
    return next(c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException")


def _usage(exc: Exception) -> str:
    message = exc.format_message()  # type: ignore[attr-defined]
    context = getattr(exc, "ctx", None)
    hint = f" (see '{context.command_path} --help')" if context is not None else ""
    return " ".join(message.split()) + hint


def run() -> None:
    """Entry point: every error ends in one ``error:`` line and exit code 2, no traceback.

    Usage errors, domain errors (:class:`~anklelab.errors.AnklelabError`) and operating-system
    errors (a full or read-only disk) are reported by the path and what was expected. SIGINT and
    SIGTERM unwind the command, so that its temporary outputs are removed, and exit with
    128 + the signal number.
    """
    from anklelab._atomic import Interrupted, note_interrupt, untemporary

    note_interrupt(None)
    handlers = {}
    unraisablehook = sys.unraisablehook
    if threading.current_thread() is threading.main_thread():
        handlers = {number: signal.signal(number, _interrupt) for number in _SIGNALS}
        sys.unraisablehook = _unraisable(unraisablehook)
    code: object = 0
    try:
        code = _command().main(prog_name="anklelab", standalone_mode=False)
    except Interrupted as exc:
        name = signal.Signals(exc.signum).name
        typer.echo(f"error: interrupted by {name}; unfinished outputs were removed", err=True)
        code = 128 + exc.signum
    except AnklelabError as exc:
        typer.echo(f"error: {untemporary(' '.join(str(exc).split()))}", err=True)
        code = 2
    except _click_error() as exc:
        typer.echo(f"error: {_usage(exc)}", err=True)
        code = 2
    except typer.Abort:
        typer.echo("error: aborted", err=True)
        code = 2
    except BrokenPipeError:  # the reader of stdout went away (`| head`): nothing to say
        sys.stdout = open(os.devnull, "w")  # keeps interpreter shutdown quiet
        code = 1
    except OSError as exc:
        typer.echo(f"error: {_os_error(exc)}", err=True)
        code = 2
    except MemoryError:
        typer.echo("error: out of memory; try a smaller input or a larger machine", err=True)
        code = 2
    finally:
        for number, handler in handlers.items():
            signal.signal(number, handler)
        sys.unraisablehook = unraisablehook
    raise SystemExit(code if isinstance(code, int) else 0)
