"""The scoreboard's rule (``jaxdamp.analysis.verdicts``) on hand-computed cases, and every
recorded verdict of ``experiments/scoreboard/*.toml`` recomputed from its record."""

import math
import tomllib

import pytest

from experiments import scoreboard
from jaxdamp.analysis.stats import t_quantile
from jaxdamp.analysis.verdicts import Check, Outcome, equivalence_margin, outcome, row_verdict


def test_equal_uses_statistics_systematics_and_welch_satterthwaite():
    # B4's case: M_ef 2.362 ± 0.00028 (3 beds) against M = 2.37
    c = Check(test="equal", estimate=2.362, se=0.00028, n=3, target=2.37)
    bare = outcome(c)
    assert bare.result == "fail"  # 28.6 SE, no systematics: ν = 2, k = 4.303
    assert bare.h == pytest.approx(t_quantile(0.975, 2) * 0.00028)
    with_budget = outcome(c, systematic=0.03)  # 3 % of 2.362 = 0.0709 ≫ 0.00028
    u = math.hypot(0.00028, 0.03 * 2.362)
    nu = u ** 4 / (0.00028 ** 4 / 2)
    assert with_budget.u == pytest.approx(u)
    assert with_budget.h == pytest.approx(t_quantile(0.975, nu) * u)
    assert with_budget.result == "pass"
    # the source's own uncertainty enters in quadrature
    src = outcome(Check(test="equal", estimate=0.0374, se=0.00003, n=3, target=0.039,
                        target_u=0.0005))
    assert src.u == pytest.approx(math.hypot(0.00003, 0.0005))
    assert src.result == "fail"  # 0.0016 > 1.96·0.0005


def test_direction_passes_fails_or_cannot_tell():
    kw = dict(se=0.01, n=5, target=0.0, level=1.0)
    assert outcome(Check(test="above", estimate=0.2, **kw)).result == "pass"
    assert outcome(Check(test="above", estimate=-0.2, **kw)).result == "fail"
    assert outcome(Check(test="above", estimate=0.01, **kw)).result == "undecided"
    assert outcome(Check(test="below", estimate=-0.2, **kw)).result == "pass"
    # a systematic of 5 % of the compared level (1.0) makes a 0.08 difference undecided
    assert outcome(Check(test="above", estimate=0.08, **kw), systematic=0.05).result \
        == "undecided"
    # one run: k = 2 on u without s
    one = outcome(Check(test="above", estimate=0.08, n=1, level=1.0), systematic=0.03)
    assert (one.result, one.replicated, one.h) == ("pass", False, pytest.approx(0.06))


def test_equivalence_is_two_one_sided_tests_against_the_margin():
    assert equivalence_margin(2.0, 0.03) == pytest.approx(0.06)
    assert equivalence_margin(2.0, 0.002) == pytest.approx(0.02)  # never below 1 %
    assert equivalence_margin(2.0, 0.002, source_scatter=0.05) == pytest.approx(0.10)
    h = t_quantile(0.95, 2) * 0.005  # 0.0146
    c = dict(target=1.0, n=3, level=1.0)
    o = outcome(Check(test="equivalent", estimate=1.02, se=0.005, **c), systematic=0.03)
    assert (o.result, o.h, o.m) == ("undecided", pytest.approx(h), pytest.approx(0.03))
    assert outcome(Check(test="equivalent", estimate=1.02, se=0.001, **c),
                   systematic=0.03).result == "pass"
    assert outcome(Check(test="equivalent", estimate=1.10, se=0.005, **c),
                   systematic=0.03).result == "fail"
    # a tiny SE no longer turns "unchanged" into "changed": 0.5 % at 10 SE is equivalent
    assert outcome(Check(test="equivalent", estimate=1.005, se=0.0005, **c),
                   systematic=0.02).result == "pass"


def test_bounded_is_a_tolerance():
    assert outcome(Check(test="bounded", estimate=0.714286, target=5 / 7, tol=1e-6)).result \
        == "pass"
    assert outcome(Check(test="bounded", estimate=0.72, target=5 / 7, tol=1e-6)).result \
        == "fail"
    with pytest.raises(ValueError, match="tol"):
        Check(test="bounded", estimate=1.0)
    with pytest.raises(ValueError, match="test = 'same'"):
        Check(test="same", estimate=1.0)


def _o(result, replicated=True):
    return Outcome(result, 0.0, 0.0, 0.0, replicated=replicated)


@pytest.mark.parametrize("kind, results, complete, expected", [
    ("claim", [_o("pass"), _o("pass")], True, "reproduced"),
    ("claim", [_o("pass"), _o("pass")], False, "partly"),
    ("claim", [_o("pass"), _o("pass", replicated=False)], True, "partly (no error bar)"),
    ("claim", [_o("fail", replicated=False)], True, "not reproduced (single run)"),
    ("claim", [_o("pass"), _o("fail", replicated=False)], True, "partly (no error bar)"),
    ("claim", [_o("pass"), _o("fail")], True, "partly"),
    ("claim", [_o("pass"), _o("undecided")], True, "partly"),
    ("claim", [_o("undecided"), _o("undecided")], True, "undecided"),
    ("claim", [_o("fail"), _o("undecided")], True, "not reproduced"),
    ("claim", [_o("fail")], True, "not reproduced"),
    ("input", [_o("pass")], True, "partly (deterministic)"),
    ("deterministic", [_o("fail")], True, "not reproduced"),
    ("not comparable", [], True, "not comparable"),
    ("method", [_o("pass"), _o("pass")], True, "pass"),
    ("method", [_o("pass"), _o("undecided")], True, "undecided"),
    ("method", [_o("pass"), _o("fail")], True, "fail"),
])
def test_row_verdicts_follow_from_the_checks(kind, results, complete, expected):
    assert row_verdict(kind, results, complete) == expected


def test_a_claim_without_checks_is_refused():
    with pytest.raises(ValueError, match="at least one check"):
        row_verdict("claim", [])


def test_every_recorded_verdict_is_the_rules():
    sections, budget = scoreboard.load_sections(), scoreboard.load_budget()
    assert sum(len(s["row"]) for s in sections.values()) >= 114
    assert scoreboard.mismatches(sections, budget) == []


def test_the_readme_is_the_generated_one():
    sections, budget = scoreboard.load_sections(), scoreboard.load_budget()
    with open(scoreboard.README) as fh:
        assert fh.read() == scoreboard.render(sections, budget), \
            "experiments/README.md is stale: run python -m experiments.scoreboard"


def test_a_record_that_breaks_the_schema_names_the_row_and_the_key():
    budget = {"u": lambda point, q=None: 0.0}
    row = dict(id="Z9", claim="c", where="w", source_value="v", ours="o", verdict="partly",
               experiment="e", colour="red")
    with pytest.raises(scoreboard.RecordError, match=r"Z9.*colour"):
        scoreboard.evaluate(row, budget)
    row.pop("colour")
    row["check"] = [dict(test="equal", estimate=1.0, sigma=0.1)]
    with pytest.raises(scoreboard.RecordError, match=r"Z9.*sigma"):
        scoreboard.evaluate(row, budget)
    row["check"] = [dict(test="equal", estimate=1.0, systematics="everywhere")]
    with pytest.raises(scoreboard.RecordError, match=r"Z9.*everywhere"):
        scoreboard.evaluate(row, budget)


def test_beds_that_agree_exactly_are_still_replicated():
    # 0 lid hits on each of 3 beds: se = 0, n = 3 — not "one run"
    o = outcome(Check(test="equal", estimate=0.0, se=0.0, n=3, target=0.0))
    assert (o.result, o.replicated) == ("pass", True)
    o = outcome(Check(test="below", estimate=0.0, se=0.0, n=3, target=0.5, level=0.5),
                systematic=0.02)
    assert (o.result, o.h) == ("pass", pytest.approx(1.959964 * 0.01, rel=1e-5))


def test_a_section_written_back_reads_the_same():
    for letter, section in scoreboard.load_sections().items():
        assert tomllib.loads(scoreboard.dump_section(section, letter)) == section, letter
