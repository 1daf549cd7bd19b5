"""The experiments: each module is one study on top of the library, run as a script.

    python experiments/<name>.py [--quick] [--out DIR] [--no-progress]
    python -m experiments.<name> ...                 # the same, as a module

Every study computes, judges and writes ``data.h5`` (:mod:`jaxdamp.io.study`), figures and
``summary.md`` into ``DIR`` (default ``experiments/<name>/``) through
:mod:`jaxdamp.studies.scaffold` (the command line, provenance, the result file, figures,
tables, the one estimate and formatter). ``README.md`` here is the scoreboard of the sources'
claims against these studies.
"""
