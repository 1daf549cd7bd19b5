"""The scoreboard as data: every claim a record, every verdict recomputed by the rule, the README
generated. ``python -m experiments.scoreboard [--check] [--verdicts] [--only A,B]``.

A tool, not a study: it computes nothing, it reads records and the systematic budget. Records
live in ``experiments/scoreboard/<S>.toml`` (one file per section, in
:data:`SECTIONS` order), with ``preamble.md`` and ``notes.md`` around the tables. Each file has
a ``title``, an ``intro`` and ``[[row]]`` records (``preamble.md``, the tallies and the
systematic budget, ``conventions.md``, the sections, ``notes.md`` make the README):

=================  ==========================================================================
``id``             the claim's id (``A1`` …)
``claim``          the claim, in the source's sense
``where``          where the source makes it
``source_value``   the source's number, or "qualitative"
``ours``           our numbers, quoted from the named experiment's summary or data
``kind``           ``claim`` (default), ``input``, ``deterministic``, ``not comparable``,
                   ``method`` (a check of our own method: tallied apart)
``complete``       whether the checks cover the whole claim (default true)
``systematics``    the row's calibrated point: ``thesis_optimum``, ``paper_reference``,
                   ``far`` (rows far from both: the larger budget) or ``none``, optionally
                   with a quantity (``thesis_optimum/f_res``, ``far/M_ef``: see
                   :func:`experiments.systematics.relative_uncertainty`); the checks' default
``verdict``        the verdict, as the rule gives it (the test recomputes it)
``qualifier``      words after the verdict, e.g. "(3 beds)" (optional)
``reason``         why, in words, after the verdict
``was``            the verdict before issue 36's re-derivation (optional)
``experiment``     the command and summary that produced ``ours``
``[[row.check]]``  the comparisons (:class:`jaxdamp.analysis.verdicts.Check`: ``test``,
                   ``estimate``, ``se``, ``n``, ``target``, ``target_u``, ``level``,
                   ``margin``, ``tol``, ``systematics``, ``what``), plus ``source_scatter``
                   (the source's relative scatter, for an equivalence margin)
=================  ==========================================================================

The systematic budget (relative standard uncertainties) comes from
``experiments/systematics/data.h5`` (:func:`experiments.systematics.budget`). ``--verdicts``
prints every row's recorded and recomputed verdict; ``--check`` writes nothing and fails
if a recorded verdict differs from the rule's or the README is not the one generated.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tomllib

FOLDER = os.path.dirname(os.path.abspath(__file__))
HERE = os.path.dirname(FOLDER)  # experiments/
README = os.path.join(HERE, "README.md")
#: Section files in table order, and which source each counts for.
SECTIONS = {"A": "thesis", "B": "thesis", "C": "thesis", "D": "thesis", "E": "thesis",
            "F": "thesis", "P": "paper", "S": "SPEC", "M": "method"}
ROW_KEYS = {"id", "claim", "where", "source_value", "ours", "kind", "complete", "systematics",
            "verdict", "qualifier", "reason", "was", "experiment", "check"}
CHECK_KEYS = {"test", "estimate", "se", "n", "target", "target_u", "level", "margin", "tol",
              "systematics", "what", "source_scatter"}
POINTS = ("thesis_optimum", "paper_reference", "far", "none")


class RecordError(ValueError):
    """A record that does not follow the schema (the message names the row and the key)."""


def load_sections(folder: str = FOLDER, only=None) -> dict:
    """``{letter: {"title", "intro", "row": [...]}}`` of every section file present (or of the
    letters ``only``)."""
    out = {}
    for letter in only or SECTIONS:
        path = os.path.join(folder, f"{letter}.toml")
        if os.path.isfile(path):
            with open(path, "rb") as fh:
                out[letter] = tomllib.load(fh)
    return out


def load_budget(path: str = os.path.join(HERE, "systematics", "data.h5")) -> dict:
    """The systematics study's budget (:func:`experiments.systematics.budget`) read from its data
    file: ``{"table": budget, "u": relative_uncertainty(point, quantity)}``."""
    from experiments import systematics
    from jaxdamp.io.study import load

    if not os.path.isfile(path):
        raise FileNotFoundError(f"{path}: run `python experiments/systematics.py` first (the "
                                "scoreboard's systematic budget)")
    b = systematics.budget(load(path))
    return {"table": b, "quantities": systematics.QUANTITIES,
            "u": lambda point, q=None: systematics.relative_uncertainty(b, point, q)}


def systematic(budget: dict, key: str, row_id: str) -> float:
    """The relative standard uncertainty of a check's ``systematics`` key, ``point`` or
    ``point/quantity`` (:func:`experiments.systematics.relative_uncertainty`)."""
    point, _, quantity = key.partition("/")
    if point not in POINTS:
        raise RecordError(f"row {row_id}: systematics = {key!r}; the point is one of {POINTS}")
    try:
        return budget["u"](point, quantity or None)
    except KeyError as err:
        raise RecordError(f"row {row_id}: {err.args[0]}") from None


ROW_ORDER = ("id", "claim", "where", "source_value", "ours", "kind", "complete", "systematics",
             "verdict", "qualifier", "reason", "was", "experiment")
CHECK_ORDER = ("what", "test", "estimate", "se", "n", "target", "target_u", "level", "margin",
               "tol", "source_scatter", "systematics")


def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    return json.dumps(str(v), ensure_ascii=False)


def dump_section(section: dict, letter: str) -> str:
    """A section as its TOML file (the inverse of :func:`load_sections` for one file: keys in
    :data:`ROW_ORDER` and :data:`CHECK_ORDER`), for tools that edit records."""
    intro = section.get("intro", "").strip().replace("\\", "\\\\").replace('"""', '""\\"')
    out = [f"# The scoreboard's section {letter}: one [[row]] per claim (schema: "
           "experiments/scoreboard/__init__.py).", "", f"title = {_toml_value(section['title'])}",
           f'intro = """\n{intro}\n"""']
    for row in section.get("row", []):
        out += ["", "[[row]]"]
        out += [f"{k} = {_toml_value(row[k])}" for k in ROW_ORDER if k in row]
        for c in row.get("check", []):
            out += ["", "[[row.check]]"]
            out += [f"{k} = {_toml_value(c[k])}" for k in CHECK_ORDER if k in c]
    return "\n".join(out) + "\n"


def checks_of(row: dict):
    """The row's :class:`~jaxdamp.analysis.verdicts.Check` s with their source scatter."""
    from jaxdamp.analysis.verdicts import Check

    out = []
    for c in row.get("check", []):
        bad = set(c) - CHECK_KEYS
        if bad:
            raise RecordError(f"row {row['id']}: check keys {sorted(bad)} unknown; "
                              f"allowed {sorted(CHECK_KEYS)}")
        kw = {k: v for k, v in c.items() if k != "source_scatter"}
        kw.setdefault("systematics", row.get("systematics", "none"))
        try:
            out.append((Check(**kw), float(c.get("source_scatter", 0.0))))
        except (TypeError, ValueError) as err:
            raise RecordError(f"row {row['id']}: {err}") from None
    return out


def evaluate(row: dict, budget: dict):
    """``(verdict, [(check, outcome)])`` of one record by the rule."""
    from jaxdamp.analysis.verdicts import outcome, row_verdict

    bad = set(row) - ROW_KEYS
    if bad:
        raise RecordError(f"row {row.get('id')}: keys {sorted(bad)} unknown; allowed "
                          f"{sorted(ROW_KEYS)}")
    pairs = [(c, outcome(c, systematic(budget, c.systematics, row["id"]), scatter))
             for c, scatter in checks_of(row)]
    try:
        verdict = row_verdict(row.get("kind", "claim"), [o for _, o in pairs],
                              row.get("complete", True))
    except ValueError as err:
        raise RecordError(f"row {row['id']}: {err}") from None
    return verdict, pairs


def _num(x: float) -> str:
    return "0" if x == 0 else f"{x:.3g}" if 1e-3 <= abs(x) < 1e4 else f"{x:.2e}"


def describe(check, o) -> str:
    """One check as the table shows it: what, the test, the difference and its interval."""
    from jaxdamp.analysis.uncertainty import pm

    what = f"{check.what}: " if check.what else ""
    if check.test == "bounded":
        return f"{what}|x − y| = {_num(abs(o.d))} ≤ {_num(check.tol)}? → {o.result}"
    if check.test == "equivalent":
        return (f"{what}equivalent: d = {pm(o.d, o.h, '.3g', '.3g')} (90 %) within "
                f"±{_num(o.m)}? → {o.result}")
    sign = {"equal": "=", "above": ">", "below": "<"}[check.test]
    rep = "" if o.replicated else ", one run"
    return (f"{what}x {sign} {_num(check.target)}: d = {pm(o.d, o.h, '.3g', '.3g')} (95 %, u "
            f"incl. `{check.systematics}` budget{rep}) → {o.result}")


def tally(sections: dict, budget: dict) -> dict:
    """``{letter: {verdict: count}}`` of the recomputed verdicts."""
    from jaxdamp.analysis.verdicts import base_verdict

    out = {}
    for letter, sec in sections.items():
        counts = {}
        for row in sec.get("row", []):
            v = base_verdict(evaluate(row, budget)[0])
            counts[v] = counts.get(v, 0) + 1
        out[letter] = counts
    return out


def _cell(text: str) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def render(sections: dict, budget: dict, folder: str = FOLDER) -> str:
    """The README: preamble, tallies, the budget, each section's table, the notes."""
    from jaxdamp.analysis.uncertainty import pm
    from jaxdamp.analysis.verdicts import METHOD_VERDICTS, VERDICTS

    with open(os.path.join(folder, "preamble.md")) as fh:
        lines = [fh.read().rstrip(), ""]
    counts = tally(sections, budget)
    n_rows = sum(len(s.get("row", [])) for s in sections.values())
    lines += [f"**Tally** ({n_rows} rows; recomputed from the records by "
              "`python -m experiments.scoreboard`):", "",
              "| section | " + " | ".join(VERDICTS) + " |",
              "|---" * (len(VERDICTS) + 1) + "|"]
    by_source: dict = {}
    for letter, sec in sections.items():
        if SECTIONS[letter] == "method":
            continue
        c = counts[letter]
        lines.append(f"| {sec['title'].split(':')[0]} | "
                     + " | ".join(str(c.get(v, 0)) for v in VERDICTS) + " |")
        src = by_source.setdefault(SECTIONS[letter], {})
        for v, k in c.items():
            src[v] = src.get(v, 0) + k
    for src, c in by_source.items():
        lines.append(f"| **{src}** | " + " | ".join(f"**{c.get(v, 0)}**" for v in VERDICTS)
                     + " |")
    if "M" in counts:
        c = counts["M"]
        lines += ["", "Method checks (section M, not claims of a source): "
                  + ", ".join(f"{c.get(v, 0)} {v}" for v in METHOD_VERDICTS) + "."]
    table, cols = budget["table"], [(p, q) for p, qs in budget["quantities"].items() for q in qs]
    lines += ["", "**The systematic budget** (`python experiments/systematics.py` → "
              "[systematics](systematics/summary.md)): relative standard uncertainty per term, "
              "u = sqrt(δ² + SE²) of the measured shift δ, added in quadrature. A check names "
              "its point and quantity (`thesis_optimum/f_res`, `far/M_ef`: M_ef takes twice "
              "f_res's, C_ef Z_res's); `far` takes the larger of the points' values, plain "
              "`far` the larger of Z's and ⟨E_d⟩'s:", "",
              "| term | " + " | ".join(f"{p.replace('_', ' ')}: {table[p][q]['name']}"
                                      for p, q in cols) + " |",
              "|---" * (len(cols) + 1) + "|"]
    for term in table["thesis_optimum"]["Z_res"]["terms"]:
        cells = []
        for p, q in cols:
            v = table[p][q]["terms"][term]
            cells.append(pm(v["delta"], v["ci95"], "+.2f", ".2f", scale=100, unit="%")
                         + f" → u = {100 * v['u']:.2f} %" if isinstance(v, dict) else _cell(v))
        lines.append(f"| {term.replace('_', ' ')} | " + " | ".join(cells) + " |")
    lines.append("| **total** | " + " | ".join(
        f"**{100 * table[p][q]['total']:.2f} %**" for p, q in cols) + " |")
    lines.append("")
    with open(os.path.join(folder, "conventions.md")) as fh:
        lines += [fh.read().rstrip(), ""]
    for letter, sec in sections.items():
        lines += [f"## {sec['title']}", ""]
        if sec.get("intro", "").strip():
            lines += [sec["intro"].strip(), ""]
        lines += ["| claim | source (where) | source's number | ours | checks (by the rule) | "
                  "verdict | experiment / command |", "| --- | --- | --- | --- | --- | --- | --- |"]
        for row in sec.get("row", []):
            verdict, pairs = evaluate(row, budget)
            checks = "; ".join(describe(c, o) for c, o in pairs) or "—"
            qual = f" {row['qualifier']}" if row.get("qualifier") else ""
            reason = row.get("reason", "").strip()
            if reason and not reason.startswith((":", ",", ";", ".")):
                reason = ": " + reason
            lines.append("| " + " | ".join(_cell(x) for x in (
                f"**{row['id']}** {row['claim']}", row["where"], row["source_value"],
                row["ours"], checks, f"**{verdict}**{qual}{reason}", row["experiment"])) + " |")
        lines.append("")
    with open(os.path.join(folder, "notes.md")) as fh:
        lines.append(fh.read().rstrip())
    return "\n".join(lines) + "\n"


def mismatches(sections: dict, budget: dict) -> list[str]:
    """Rows whose recorded ``verdict`` is not the rule's."""
    out = []
    for sec in sections.values():
        for row in sec.get("row", []):
            got = evaluate(row, budget)[0]
            if row.get("verdict") != got:
                out.append(f"{row['id']}: recorded {row.get('verdict')!r}, the rule gives {got!r}")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true",
                    help="write nothing; fail if a verdict or the README is out of date")
    ap.add_argument("--verdicts", action="store_true",
                    help="print each row's recorded and recomputed verdict and its checks")
    ap.add_argument("--only", default="", help="with --verdicts: these sections (e.g. A,E)")
    ap.add_argument("--systematics", default=os.path.join(HERE, "systematics", "data.h5"),
                    help="the systematics study's data file (default: the committed one)")
    args = ap.parse_args(argv)
    try:
        only = [x.strip() for x in args.only.split(",") if x.strip()] or None
        sections, budget = load_sections(only=only), load_budget(args.systematics)
        if args.verdicts:
            for sec in sections.values():
                for row in sec.get("row", []):
                    v, pairs = evaluate(row, budget)
                    flag = "" if v == row.get("verdict") else "   <-- recorded " + repr(
                        row.get("verdict"))
                    print(f"{row['id']:5s} {v}{flag}")
                    for c, o in pairs:
                        print(f"        {describe(c, o)}")
            return 0
        bad = mismatches(sections, budget)
        text = render(sections, budget)
    except (RecordError, FileNotFoundError) as err:
        print(f"scoreboard: {err}", file=sys.stderr)
        return 2
    if args.check:
        with open(README) as fh:
            stale = fh.read() != text
        for line in bad:
            print(line, file=sys.stderr)
        if stale:
            print(f"{README} is not the generated one: run python -m experiments.scoreboard",
                  file=sys.stderr)
        return 1 if bad or stale else 0
    for line in bad:
        print(line, file=sys.stderr)
    with open(README, "w") as fh:
        fh.write(text)
    print(f"wrote {README}" + (f"; {len(bad)} recorded verdicts differ from the rule"
                               if bad else ""))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
