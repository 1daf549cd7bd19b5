"""The ``jaxdamp`` command line: one module per subcommand (``run``, ``frf``, ``optimize``,
``efficiency``) and one for the file commands (``presets``, ``info``, ``plot``, ``export``).
Side effects (files, printing) live here and in the studies; heavy imports (JAX, jax-md) happen
inside the commands, so ``--help`` and configuration errors answer at once."""

from __future__ import annotations

import argparse
import sys

from jaxdamp.cli import efficiency, files, frf, optimize, run
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
    sub = p.add_subparsers(dest="command", required=True)
    for command in (run, frf, optimize, efficiency, files):
        command.register(sub)
    return p


def main(argv=None) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as done:  # --help (0) or a usage error (2, already printed)
        return int(done.code or 0)
    try:
        return args.func(args)
    except ConfigError as err:
        print(f"jaxdamp: error: {err}", file=sys.stderr)
        return 2
    except FloatingPointError as err:
        print(f"jaxdamp: {err}", file=sys.stderr)
        return 3
    except KeyboardInterrupt:
        words = list(sys.argv[1:] if argv is None else argv)
        out = getattr(args, "out", None)
        if out and hasattr(args, "resume"):
            import shlex

            again = "jaxdamp " + shlex.join([w for w in words if w != "--resume"] + ["--resume"])
            print(f"jaxdamp: interrupted; {out} keeps every finished chunk (status "
                  f"'interrupted'). Continue with: {again}", file=sys.stderr)
        else:
            print("jaxdamp: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
