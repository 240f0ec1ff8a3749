"""Benchmark: the alternate minimization's sweeps with and without over-relaxation (Farrell & Maurini 2017).

`[fracture] over_relaxation = omega` moves the damage omega times each sweep's step (within its bounds); the
fixed point is the plain iteration's, so the answers must agree to the staggered tolerance while the sweeps
change. Two scenes of benchmarks/fracture_cost.py: the notched bar cut through (l = 0.1, h = l/4 and l/8, 30
steps) and the centre-cracked plate (h = l/2 along the crack, 16 steps to 1.3x the critical displacement), each
at omega = 1 (plain), 1.2, 1.4 and 1.6: sweeps, Newton iterations, wall time (median of 3 for the bars, one run
for the plate, after a run that compiled the forms; one core) and the answer (the bar's crack area over its
section, the plate's peak force and crack area).

Run: `OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/fracture_acceleration.py` (about 5 minutes). Writes
benchmarks/fracture_acceleration.md.
"""
from __future__ import annotations

from pathlib import Path
import statistics
import sys
import time

import fem_forms as ff

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import fracture_cost as fc  # noqa: E402

OMEGAS = (1.0, 1.2, 1.4, 1.6)


def run(scene: ff.Scene, omega: float, runs: int) -> tuple[float, dict]:
    """Median wall time of `runs` solves at over-relaxation omega (after one that compiles), and the summary."""
    scene.fracture.over_relaxation = omega
    ff.solve_static(scene)
    times, summary = [], None
    for _ in range(runs):
        t0 = time.perf_counter()
        summary = ff.solve_static(scene).summary()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), summary


def main() -> None:
    ff.quiet_jit()
    lines = ["# Over-relaxed alternate minimization (benchmarks/fracture_acceleration.py)", "",
             "| scene | omega | sweeps | Newton iterations | wall time | answer |", "|---|---|---|---|---|---|"]
    for h_over_l in (1 / 4, 1 / 8):
        for omega in OMEGAS:
            wall, s = run(fc.bar(h_over_l), omega, runs=3)
            lines.append(f"| notched bar, h = l/{round(1 / h_over_l)} | {omega:g} | {s['staggered_sweeps']} | "
                         f"{s['newton_iterations']} | {wall:.2f} s | crack area / A {s['crack_area'] / 0.01:.5f} |")
            print(lines[-1], flush=True)
    h = fc.ELL / 2
    mesh = fc.centre_crack.build(Path("/tmp/fracture_acceleration_plate.msh"), ell=fc.ELL, h_fine=h)
    for omega in OMEGAS:
        wall, s = run(fc.plate(mesh, True, h, 1e-4, steps=16), omega, runs=1)
        lines.append(f"| centre-cracked plate, h = l/2 | {omega:g} | {s['staggered_sweeps']} | "
                     f"{s['newton_iterations']} | {wall:.1f} s | peak force {s['peak_force']['pull']:.6g} N, crack "
                     f"area {s['crack_area']:.6g} m^2 |")
        print(lines[-1], flush=True)
    lines += ["", "Sweeps count every alternation of a damage and a displacement solve over all load steps; the "
              "staggered tolerance is 1e-4 (a sweep's plain step changes the damage by less), judged on the plain "
              "step in every row, so the rows converge to the same fixed point. One core; these machines vary "
              "15-35 % run to run."]
    (HERE / "fracture_acceleration.md").write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
