"""``python -m jaxdamp`` and the ``jaxdamp`` script: the command line (:mod:`jaxdamp.cli`).

Ctrl-C becomes a request (:mod:`jaxdamp.interrupt`) before the command line's own imports, so
a Ctrl-C in the first second — while ``argparse``, ``json`` and the subcommands load — is
answered like any other (exit 130, one line); only the interpreter's own start, before this
module runs, is left to Python."""

from jaxdamp import interrupt


def entry() -> None:
    interrupt.install()
    from jaxdamp.cli import entry as run_command

    run_command()


if __name__ == "__main__":
    entry()
