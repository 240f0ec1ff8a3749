"""The fast part of the verification manual (verification/run.py --fast): every fast benchmark runs as
`fem-forms run` subprocess and each of its numbers must lie within its stated tolerance of the target.
The full manual (NAFEMS LE1, the FEniCSx tutorial beam) runs with `verification/run.py`."""
import importlib.util
import sys

from helpers import ROOT

_spec = importlib.util.spec_from_file_location("verification_run", ROOT / "verification" / "run.py")
verification = importlib.util.module_from_spec(_spec)
sys.modules["verification_run"] = verification      # dataclasses look their module up
_spec.loader.exec_module(verification)


def test_fast_benchmarks_meet_their_tolerances(tmp_path):
    fast = [c for c in verification.CASES if c.fast]
    assert {"nafems_fv32", "uniaxial_tension", "modal_cantilever"} <= {c.name for c in fast}
    rows = verification.run_cases(fast, tmp_path, echo=False)
    assert len(rows) == sum(len(c.rows) for c in fast)
    bad = [f"{r['case']} {r['quantity']}: {r['status']} {r.get('note') or verification._fmt_err(r)}"
           for r in rows if r["status"] != "pass"]
    assert not bad, "\n".join(bad)


def test_a_missing_results_key_is_reported_not_available_never_passed(tmp_path):
    """A number the package does not write (here a made-up probe key) fails as "not available"."""
    case = next(c for c in verification.CASES if c.name == "uniaxial_tension")
    fake = verification.Case(case.name, case.benchmark, case.source, case.scene,
                             [verification.Row("no such key", 1.0, verification.probe("corner", "no_such_key", 0),
                                               1.0)])
    (row,) = verification.run_case(fake, tmp_path)
    assert row["status"] == "not available" and "probes.corner.no_such_key" in row["note"]


def test_readme_table_is_written_from_rows(tmp_path):
    rows = [{"case": "c", "benchmark": "b", "source": "s", "quantity": "q", "unit": "Hz", "tolerance": 0.01,
             "relative": True, "scale": 1.0, "target": 10.0, "result": 10.05, "error": 0.005, "status": "pass",
             "dofs": 12, "wall_time_s": 1.0},
            {"case": "c", "benchmark": "b", "source": "s", "quantity": "q2", "unit": "", "tolerance": 0.01,
             "relative": True, "scale": 1.0, "target": 1.0, "status": "not available", "note": "no key",
             "dofs": None, "wall_time_s": 1.0}]
    case = verification.Case("c", "b", "s", "x.toml", [], notes="n")
    path = tmp_path / "README.md"
    verification.write_readme(rows, [case], path, "cmd", 2.0)
    text = path.read_text()
    assert "| c | b | s | q | 10 Hz | 10.05 | +0.5 % | 1 % | pass | 12 | 1.0 |" in text
    assert "**not available**" in text and "1 of 2 rows pass" in text
