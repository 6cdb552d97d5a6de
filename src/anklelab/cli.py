"""The ``anklelab`` command. Each command group lives in its own module under ``commands``.

The top-level group knows each subcommand's name, where it is defined and its one-line help
(:data:`COMMANDS`), and imports a command's module only when that command is run or its own
``--help`` is shown: ``anklelab --help`` imports none of them.
"""

from __future__ import annotations

import atexit
import errno
import functools
import importlib
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Mapping, MutableMapping
from typing import Annotated, Any, ClassVar, NamedTuple, cast

import typer
from typer.core import TyperCommand, TyperGroup

from anklelab import __version__
from anklelab.errors import AnklelabError


class LazyCommand(NamedTuple):
    """A subcommand that is imported on first use.

    Attributes
    ----------
    target : str
        ``"module:name"`` of a :class:`typer.Typer` (a group of commands) or of a command
        function.
    short_help : str
        Its line in the parent's ``--help``: the command's own short help as click shows it on a
        wide terminal (the first sentence of its help). ``tests/test_cli_lazy.py`` checks that it
        equals the loaded command's, so the two cannot drift apart.
    """

    target: str
    short_help: str


class LazyCommands(MutableMapping[str, Any]):
    """A group's name -> click command mapping that imports a lazy command when it is looked up.

    Names, membership and order (the lazy commands in their table's order, then any added
    eagerly) need no import; ``mapping[name]`` (and so ``get``, ``values`` and ``items``) loads
    the command once and keeps it.

    Parameters
    ----------
    lazy : mapping of str to LazyCommand
        The lazy commands, in the order they are listed.
    load : callable
        ``load(name, entry)`` -> the click command of ``entry``.
    eager : mapping of str to click command, optional
        Commands that are already built.
    """

    def __init__(
        self,
        lazy: Mapping[str, LazyCommand],
        load: Callable[[str, LazyCommand], Any],
        eager: Mapping[str, Any] | None = None,
    ) -> None:
        self._lazy = dict(lazy)
        self._load = load
        self._loaded: dict[str, Any] = dict(eager or {})

    def __getitem__(self, name: str) -> Any:
        if name not in self._loaded:
            if name not in self._lazy:
                raise KeyError(name)
            self._loaded[name] = self._load(name, self._lazy[name])
        return self._loaded[name]

    def __setitem__(self, name: str, command: Any) -> None:
        self._loaded[name] = command

    def __delitem__(self, name: str) -> None:
        if name not in self:
            raise KeyError(name)
        self._lazy.pop(name, None)
        self._loaded.pop(name, None)

    def __contains__(self, name: object) -> bool:
        return name in self._lazy or name in self._loaded

    def __iter__(self) -> Iterator[str]:
        yield from self._lazy
        yield from (name for name in self._loaded if name not in self._lazy)

    def __len__(self) -> int:
        return len(self._lazy.keys() | self._loaded.keys())

    def listed(self, name: str) -> Any:
        """The command as the parent's ``--help`` lists it, without importing it.

        Parameters
        ----------
        name : str
            A command name of this mapping.

        Returns
        -------
        click command
            The loaded command if it was loaded, else a stand-in carrying only its short help.
        """
        if name in self._loaded:
            return self._loaded[name]
        return TyperCommand(name, help=self._lazy[name].short_help)


class LazyGroup(TyperGroup):
    """A typer group whose subcommands (:attr:`lazy`) are imported when first used.

    A subclass sets :attr:`lazy`; pass it as ``typer.Typer(cls=...)``. Looking a command up
    (:meth:`get_command`, as running it or showing its ``--help`` does) imports its module and
    converts it as ``app.add_typer``/``app.command`` would have, with this group's markup mode
    and command suggestions (typer's default ``pretty_exceptions_short``); listing the commands
    (:meth:`list_commands`, this group's ``--help``) imports nothing.
    """

    lazy: ClassVar[Mapping[str, LazyCommand]] = {}
    commands: LazyCommands

    def __init__(self, **attrs: Any) -> None:
        super().__init__(**attrs)
        self.commands = LazyCommands(self.lazy, self._load, eager=self.commands)

    def _load(self, name: str, entry: LazyCommand) -> Any:
        """Import ``entry`` and build its click command, named ``name``."""
        module, _, attribute = entry.target.partition(":")
        target = getattr(importlib.import_module(module), attribute)
        holder = typer.Typer(
            rich_markup_mode=self.rich_markup_mode,
            suggest_commands=self.suggest_commands,
            add_completion=False,
        )
        holder.callback()(_no_options)  # a group, as the real parent is
        if isinstance(target, typer.Typer):
            holder.add_typer(target, name=name)
        else:
            holder.command(name)(target)
        return cast(TyperGroup, typer.main.get_command(holder)).commands[name]

    def list_commands(self, ctx: Any) -> list[str]:
        """The command names in the order given (no import)."""
        return list(self.commands)

    def format_commands(self, ctx: Any, formatter: Any) -> None:
        """The ``Commands`` section of ``--help``, as typer writes it, from the short helps."""
        names = self.list_commands(ctx)
        listing = TyperGroup(commands={name: self.commands.listed(name) for name in names})
        TyperGroup.format_commands(listing, ctx, formatter)


def _no_options() -> None:
    """The callback of the throwaway parent that :meth:`LazyGroup._load` converts through."""


class Anklelab(LazyGroup):
    """The ``anklelab`` group."""

    lazy: ClassVar[Mapping[str, LazyCommand]] = {
        "analyze": LazyCommand(
            "anklelab.commands.analyze:analyze",
            "Ankle stiffness, damping and inertia per timing point and direction, with bootstrap.",
        ),
        "forceplate": LazyCommand(
            "anklelab.commands.forceplate:forceplate",
            "Ground reaction force, centre of pressure and free moment, one CSV table per plate.",
        ),
        "inspect": LazyCommand(
            "anklelab.commands.tree:inspect",
            "Print a file's tree: names, shapes and types, and a C3D file's channels, force "
            "platforms, events and parameters.",
        ),
        "demo": LazyCommand(
            "anklelab.commands.demo:demo",
            "Run both papers' experiments on the digital twins and compare with the papers.",
        ),
        "report": LazyCommand(
            "anklelab.commands.report:report",
            "Build a self-contained report.html (tables and figures, no network) from results.",
        ),
        "study": LazyCommand(
            "anklelab.commands.study:study",
            "Simulate and analyse every cell of a study (twin settings x analysis settings x "
            "seeds).",
        ),
        "design": LazyCommand(
            "anklelab.commands.design:design",
            "Trials per timing point for a stiffness interval of ±X % and the power to detect a "
            "Y % change between timing points, from pilot sessions of the twin.",
        ),
        "batch": LazyCommand(
            "anklelab.commands.batch:batch",
            "Analyse every session with the same settings; per-session results and a group table.",
        ),
        "platform": LazyCommand(
            "anklelab.commands.platform:app", "Inspect platform parameter sets and their sources."
        ),
        "session": LazyCommand("anklelab.commands.session:app", "Inspect sessions."),
        "import": LazyCommand(
            "anklelab.commands.imports:app",
            "Validate a session and store it as one native HDF5 file: `anklelab import SOURCE "
            "--out S.h5` for a session directory or MATLAB session file, or from C3D or any "
            "MATLAB layout through a mapping (subcommands c3d, matlab).",
        ),
        "identify": LazyCommand(
            "anklelab.commands.identify:app", "Identify platform models from recorded data."
        ),
        "simulate": LazyCommand(
            "anklelab.commands.simulate:app", "Simulate experiments on the digital twins."
        ),
        "capstan": LazyCommand(
            "anklelab.commands.capstan:app",
            "Capstan haptic ankle platform (paper 001) on its twin: gains, set-points, chirp, "
            "display envelope, torque observer, haptic rendering, terrain scenes, Z-width, "
            "teleoperation.",
        ),
    }


COMMANDS = Anklelab.lazy
"""Every subcommand of ``anklelab``: name -> where it is defined and its one-line help."""

app = typer.Typer(
    cls=Anklelab,
    help="anklelab: digital twins, control and identification for ankle actuation platforms.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
    rich_markup_mode=None,
)


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


_BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
"""One BLAS thread per process. The commands' matrix products are small, and a command runs its
own processes on the other cores (figure workers, Dask workers, trial batches): BLAS threads on
top of them took turns with the analysis for two cores, and slowed ``analyze`` of a paper-size
session from 2.3 to 3.1 s of analysis while its figure workers started."""


def run() -> None:
    """Entry point: every error ends in one ``error:`` line and exit code 2, no traceback.

    Usage errors, domain errors (:class:`~anklelab.errors.AnklelabError`) and operating-system
    errors (a full or read-only disk) are reported by the path and what was expected. SIGINT and
    SIGTERM unwind the command, so that its temporary outputs are removed, and exit with
    128 + the signal number.
    """
    from anklelab._atomic import Interrupted, forget_interrupts, untemporary

    for name in _BLAS_THREADS:  # before NumPy loads its BLAS; the user's own setting stands
        os.environ.setdefault(name, "1")
    forget_interrupts()
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


def program() -> None:
    """The ``anklelab`` program: :func:`run`, then, if the command succeeded, an immediate end of
    the process.

    A command that succeeded has closed and renamed into place everything it writes, so what a
    normal interpreter exit still does is free memory and unload modules, one object at a time:
    0.2 s after a simulation of the paper-size session, about a tenth of the command. So the exit
    handlers run, the standard streams are flushed, and the process ends there. A failed or
    interrupted command exits normally: the interpreter then waits for what it is still ending
    (figure workers being started, whose setup must not outlive this process).
    :func:`run` itself always exits normally (tests and benchmarks call it inside Python).
    """
    try:
        run()
    except SystemExit as exc:
        if exc.code not in (0, None):
            raise
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a closed pipe or stream: nothing more can be said
            pass
    os._exit(0)
