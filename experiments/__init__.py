"""The experiments: each module is one study on top of the library, run as a script.

    python experiments/<name>.py [--quick] [--out DIR] [--no-progress]
    python -m experiments.<name> ...                 # the same, as a module

Every study computes, judges and writes ``data.h5``, ``figure.png`` (or named figures) and
``summary.md`` into ``DIR`` (default ``experiments/<name>/``) through :mod:`experiments.scaffold`
(the command line, provenance, the results file, figures and the summary's first line).
``README.md`` here is the scoreboard of the sources' claims against these studies.
"""
