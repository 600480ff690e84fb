"""What the commands show on the console besides their results: notes (on stdout, or stderr for a
note that starts ``rockslide:`` and whenever stdout carries JSON), progress bars on a terminal, and
the command line a study stores in its file."""

from __future__ import annotations

import contextlib
import shlex
import sys

import click

from .. import interrupts
from .app import show_warnings


def reporter(*, err: bool = False):
    """The ``report`` of a run or a study: each note on stdout (stderr with ``err``, or for a
    ``rockslide:`` line), after the warnings held until the input was accepted."""
    def report(text: str) -> None:
        show_warnings()                 # the input is accepted: its warnings, then the notes of the work
        click.echo(text, err=err or text.startswith("rockslide:"))
    return report


def bars(*, no_progress: bool = False):
    """The ``bars`` of a study (`api.sweep_study`): tqdm's bars on a terminal's stderr only, so that
    no frames land in log files; none with ``no_progress``."""
    @contextlib.contextmanager
    def bar(description: str, total: int, unit: str, *, transient: bool = False):
        if not transient:
            show_warnings()             # the input is accepted: its warnings, then the work
        disable = True if no_progress else (not sys.stderr.isatty() if transient else None)
        if disable or not sys.stderr.isatty():      # no bar (tqdm's disable=None: none off a terminal)
            yield lambda cases: None
            return
        from tqdm import tqdm

        with tqdm(total=total, unit=unit, file=sys.stderr, desc=description, disable=disable, dynamic_ncols=True,
                  leave=not transient, smoothing=0.1) as t:
            yield t.update
    return bar


class RunProgress:
    """The ``progress`` of a single run: checks for Ctrl-C between kernel chunks and, on a terminal,
    shows a bar of the simulated time after a few seconds (a new pass restarts it)."""

    def __init__(self, name: str):
        self.name = name
        self.show = sys.stderr.isatty()
        self.bar = None
        self.last = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        if self.bar is not None:
            self.bar.close()
        return False

    def __call__(self, reached: float, end: float) -> None:
        interrupts.check()
        if not self.show:
            return
        from tqdm import tqdm

        if self.bar is None or (self.last is not None and reached < self.last):
            if self.bar is not None:
                self.bar.close()
            self.bar = tqdm(total=round(end - reached, 3), unit="s", file=sys.stderr, desc=self.name, delay=2.0,
                            dynamic_ncols=True, bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} s simulated "
                            "[{elapsed}<{remaining}]")
            self.start = reached
        self.bar.update(round(reached - self.start, 3) - self.bar.n)
        self.last = reached


def command_line(ctx, case_file, axes=()) -> str:
    """A study's command line, as stored in its file: ``axes`` (a sweep's, in the order given) first,
    then the other options given on the command line."""
    from click.core import ParameterSource

    words = ["rockslide", ctx.command.name, str(case_file)]
    for name, text in axes:
        words += [f"--{name.replace('_', '-')}", text]
    for param in ctx.command.params:
        if not isinstance(param, click.Option) or param.name in {n for n, _ in axes}:
            continue
        if ctx.get_parameter_source(param.name) is not ParameterSource.COMMANDLINE:
            continue
        value = ctx.params.get(param.name)
        if param.is_flag:
            words += [param.opts[0]] if value else []
        elif param.multiple:
            for item in value or ():
                words += [param.opts[0], str(item)]
        elif value is not None:
            words += [param.opts[0], str(value)]
    return shlex.join(words)
