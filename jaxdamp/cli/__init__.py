"""The ``jaxdamp`` command line: one module per subcommand (``run``, ``frf``, ``decay``, ``random``, ``optimize``,
``efficiency``, ``map``, ``materials``) and one for the file commands (``presets``, ``info``,
``plot``, ``export``).
Side effects (files, printing) live here and in the studies; heavy imports (JAX) happen
inside the commands, after the configuration is built and every output file is checked, so
``--help``, configuration errors and file errors answer at once.

Errors reach the user as one line (exit 2 for bad input, files and a full disk, 3 for a run
that went non-finite or an optimisation that FAILED, 130 for Ctrl-C); anything else is a bug, reported in one line naming the exception,
with its full traceback under ``jaxdamp --debug COMMAND ...``."""

from __future__ import annotations

import argparse
import os
import sys

from jaxdamp import __version__, interrupt
from jaxdamp.cli import decay, efficiency, files, frf, maps, materials, optimize, random, run
from jaxdamp.config import ConfigError


class _Parser(argparse.ArgumentParser):
    """Usage errors in one line, with where to look (the subcommands inherit the class)."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see `{self.prog} --help`)\n")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="jaxdamp",
        description="Simulate granular (particle) dampers with a JAX discrete-element model.",
        epilog="Run `jaxdamp COMMAND --help` for each command's options and examples.",
    )
    p.add_argument("--version", action="version", version=f"jaxdamp {__version__}",
                   help="print the version and exit")
    p.add_argument("--debug", action="store_true",
                   help="show the full Python traceback of an error (for bug reports)")
    p.add_argument("--no-size-check", action="store_true",
                   help="run batches whose estimated memory or file size exceeds what this "
                        "machine has (default: refuse them before computing, in one line)")
    sub = p.add_subparsers(dest="command", required=True)
    for command in (run, frf, decay, random, optimize, efficiency, maps, files, materials):
        command.register(sub)
    return p


def main(argv=None) -> int:
    """Run one ``jaxdamp`` command; returns its exit status. Ctrl-C is a request from this
    first line on (:mod:`jaxdamp.interrupt`); every output is claimed for this process from its
    pre-compute check to the end (:mod:`jaxdamp.io.claims`)."""
    interrupt.install()
    try:
        return _main(argv)
    finally:
        held = sys.modules.get("jaxdamp.io.claims")  # imported by the commands that write
        if held is not None:
            held.release_all()
        sizes = sys.modules.get("jaxdamp.engine.budget")
        if sizes is not None:
            sizes.ENFORCE = True
        interrupt.uninstall()


def _main(argv) -> int:
    args = None
    try:
        args = build_parser().parse_args(argv)
        interrupt.check()
    except SystemExit as done:  # --help (0) or a usage error (2, already printed)
        return int(done.code or 0)
    except KeyboardInterrupt:
        print(interrupted_message(args, []), file=sys.stderr)
        return 130
    debug = getattr(args, "debug", False)
    try:
        if args.no_size_check:
            from jaxdamp.engine import budget

            budget.ENFORCE = False
        return args.func(args)
    except ConfigError as err:
        if debug:
            raise
        print(f"jaxdamp: error: {err}", file=sys.stderr)
        return 2
    except FloatingPointError as err:
        if debug:
            raise
        print(f"jaxdamp: {err}", file=sys.stderr)
        return 3
    except OSError as err:  # a file the checks could not foresee (disk full, removed folder)
        if debug:
            raise
        print(f"jaxdamp: error: {_one_line(err)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(interrupted_message(args, list(sys.argv[1:] if argv is None else argv)),
              file=sys.stderr)
        return 130
    except Exception as err:  # a bug: one line, the traceback with --debug
        if debug:
            raise
        print(f"jaxdamp: internal error (a bug, please report it): {type(err).__name__}: "
              f"{_one_line(err)}; run again as `jaxdamp --debug ...` for the traceback",
              file=sys.stderr)
        return 1


def interrupted_message(args, words) -> str:
    """What Ctrl-C left, naming only files that exist: the command that continues a file with a
    checkpoint, or that nothing was written (or replaced)."""
    out = getattr(args, "out", None)
    if not out:
        return "jaxdamp: interrupted"
    if not os.path.exists(out):
        return (f"jaxdamp: interrupted before {out} was written (nothing to resume); run the "
                "command again to start over")
    from jaxdamp.io import claims
    from jaxdamp.io.common import has_checkpoint

    continues = getattr(args, "resume", False)
    if not continues and not claims.changed(out):
        return f"jaxdamp: interrupted before {out} was replaced; it was left as it was"
    if _is_optimiser_log(out):
        return (f"jaxdamp: interrupted; {out} keeps the iterates so far (status 'running'); a "
                "search does not resume: run the command again with --overwrite")
    if not has_checkpoint(out):
        return (f"jaxdamp: interrupted before the first chunk was finished: {out} holds no "
                "checkpoint to continue; run the command again with --overwrite")
    if not hasattr(args, "resume"):  # efficiency: the same command continues its sweeps
        return (f"jaxdamp: interrupted; {out} keeps every finished chunk (status "
                "'interrupted'). Run the same command again to continue it")
    import shlex

    again = "jaxdamp " + shlex.join([w for w in words if w not in ("--resume", "--overwrite")]
                                    + ["--resume"])
    return (f"jaxdamp: interrupted; {out} keeps every finished chunk (status 'interrupted'). "
            f"Continue with: {again}")


def _is_optimiser_log(path) -> bool:
    import h5py

    from jaxdamp.io.describe import file_family

    try:
        with h5py.File(path, "r") as h5:
            return file_family(h5) == "jaxdamp-optimize"
    except OSError:
        return False


def entry() -> None:
    """The console script: :func:`main`, then an exit that skips the interpreter's teardown
    after an error or Ctrl-C (XLA's and numba's threads may still be alive then, and a
    teardown under them can crash after the message was printed; every file was closed or
    flushed by then)."""
    code = main()
    if code == 0:  # the work is done and written: a Ctrl-C now cannot lose anything
        import signal

        signal.signal(signal.SIGINT, signal.SIG_IGN)
        sys.exit(0)
    try:
        sys.stdout.flush()
        sys.stderr.flush()
    finally:
        os._exit(code)


def _one_line(err: BaseException) -> str:
    return " ".join(str(err).split()) or type(err).__name__


if __name__ == "__main__":
    entry()
