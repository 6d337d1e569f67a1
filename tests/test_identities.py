"""Every identity of the generated functions (report/identities.py, the same list that fills
the report's verification table) holds within its bound at the suite's seeded random
admissible points."""
import pytest

from report.identities import CHECKS, Context, evaluate


@pytest.fixture(scope="module")
def context(model):
    return Context(model)


@pytest.mark.parametrize("check", CHECKS, ids=[f"{c.group}: {c.tex}" for c in CHECKS])
def test_identity(check, context, points):
    result = evaluate(check, context, points)
    if result.skipped:
        pytest.skip(result.skipped)
    assert result.points == len(points)
    relation = ">" if check.kind == "min" else "<="
    assert result.ok, (f"{check.group}: {check.tex}: {result.value:.3e} not {relation} "
                       f"{check.bound:g} over {result.points} points")
