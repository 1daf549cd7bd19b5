"""The ``jaxdamp`` command line: one module per subcommand (``run``, ``frf``, ``decay``, ``random``, ``optimize``,
``efficiency``) and one for the file commands (``presets``, ``info``, ``plot``, ``export``).
Side effects (files, printing) live here and in the studies; heavy imports (JAX) happen
inside the commands, after the configuration is built and every output file is checked, so
``--help``, configuration errors and file errors answer at once.

Errors reach the user as one line (exit 2 for bad input and files, 3 for a run that went
non-finite, 130 for Ctrl-C); anything else is a bug, reported in one line naming the exception,
with its full traceback under ``jaxdamp --debug COMMAND ...``."""

from __future__ import annotations

import argparse
import sys

from jaxdamp.cli import decay, efficiency, files, frf, optimize, random, run
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
    p.add_argument("--debug", action="store_true",
                   help="show the full Python traceback of an error (for bug reports)")
    sub = p.add_subparsers(dest="command", required=True)
    for command in (run, frf, decay, random, optimize, efficiency, files):
        command.register(sub)
    return p


def main(argv=None) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as done:  # --help (0) or a usage error (2, already printed)
        return int(done.code or 0)
    debug = getattr(args, "debug", False)
    try:
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
        words = list(sys.argv[1:] if argv is None else argv)
        out = getattr(args, "out", None)
        if out and hasattr(args, "resume"):
            import shlex

            again = "jaxdamp " + shlex.join([w for w in words if w not in ("--resume", "--overwrite")]
                                            + ["--resume"])
            print(f"jaxdamp: interrupted; {out} keeps every finished chunk (status "
                  f"'interrupted'). Continue with: {again}", file=sys.stderr)
        else:
            print("jaxdamp: interrupted", file=sys.stderr)
        return 130
    except Exception as err:  # a bug: one line, the traceback with --debug
        if debug:
            raise
        print(f"jaxdamp: internal error (a bug, please report it): {type(err).__name__}: "
              f"{_one_line(err)}; run again as `jaxdamp --debug ...` for the traceback",
              file=sys.stderr)
        return 1


def _one_line(err: BaseException) -> str:
    return " ".join(str(err).split()) or type(err).__name__


if __name__ == "__main__":
    sys.exit(main())
