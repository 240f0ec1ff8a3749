"""The listener's pressure by the simple-source integral (ours) against a boundary element solve.

A boundary element solve of the exterior Helmholtz problem (bempp-cl, Burton-Miller formulation, P1
pressure, piecewise constant normal velocity on the FE mesh's boundary triangles) is exact up to its
discretisation, also for a body that is not compact; the simple-source integral (output/radiation.py)
leaves out the body's own scattering. Both take the same FE mode shapes of the struck bar of
demos/scenes/struck_bar.toml (free, 300 x 30 x 10 mm) and give the pressure at the issue's listener
[0.0, 0.5, 0.2]; the table compares their levels per mode and their cost. A pulsating sphere checks
the BEM against its closed form first.

bempp-cl is NOT a project dependency: run this with a venv that has it, e.g.
`python3 -m venv --system-site-packages /tmp/bem && /tmp/bem/bin/pip install bempp-cl numba` then
`PYTHONPATH=. OPENBLAS_NUM_THREADS=1 /tmp/bem/bin/python benchmarks/radiation_bem.py [--write]`.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path
import sys
import time

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
RHO, C = 1.2, 343.0
LISTENER = np.array([0.0, 0.5, 0.2])


def outward(points: np.ndarray, tris: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """Triangles reordered so that their normals point away from `centre` (a convex body)."""
    a, b, c = (points[tris[:, i]] for i in range(3))
    n = np.cross(b - a, c - a)
    flip = np.einsum("ij,ij->i", n, (a + b + c) / 3 - centre) < 0
    tris = tris.copy()
    tris[flip] = tris[flip][:, [0, 2, 1]]
    return tris


def bem_pressure(points: np.ndarray, tris: np.ndarray, un: np.ndarray, omega: float, at: np.ndarray) -> complex:
    """Pressure at `at` radiated by the normal displacement amplitudes `un` (one per triangle) at omega,
    time factor e^{-i omega t} (bempp's Green's function e^{ikR} / 4 pi R): Burton-Miller,
    (1/2 - K + eta W) p = -(V + eta (1/2 + K')) g, g = dp/dn = rho omega^2 u_n, eta = i / k."""
    import bempp_cl.api as bempp
    k = omega / C
    grid = bempp.Grid(points.T.copy(), tris.T.copy())
    assert np.array_equal(grid.elements, tris.T), "bempp reordered the triangles: u_n would be misplaced"
    p1, dp0 = bempp.function_space(grid, "P", 1), bempp.function_space(grid, "DP", 0)
    ops, eta = bempp.operators.boundary, 1j / k
    lhs = (0.5 * ops.sparse.identity(p1, p1, p1) - ops.helmholtz.double_layer(p1, p1, p1, k)
           + eta * ops.helmholtz.hypersingular(p1, p1, p1, k))
    rhs_op = -(ops.helmholtz.single_layer(dp0, p1, p1, k)
               + eta * (0.5 * ops.sparse.identity(dp0, p1, p1) + ops.helmholtz.adjoint_double_layer(dp0, p1, p1, k)))
    g = bempp.GridFunction(dp0, coefficients=RHO * omega**2 * un.astype(complex))
    p = bempp.linalg.lu(lhs, rhs_op * g)
    pots = bempp.operators.potential.helmholtz
    x = at.reshape(3, 1)
    return complex((pots.double_layer(p1, x, k) * p - pots.single_layer(dp0, x, k) * g)[0, 0])


def sphere_check(h: float) -> list:
    """BEM on a meshed sphere against the pulsating sphere's closed form: (ka, |p_bem / p_exact|)."""
    import gmsh
    a = 0.1
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.model.occ.addSphere(0, 0, 0, a)
    gmsh.model.occ.synchronize()
    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.model.mesh.generate(2)
    _, xyz, _ = gmsh.model.mesh.getNodes()
    _, _, nodes = gmsh.model.mesh.getElements(2)
    gmsh.finalize()
    pts = xyz.reshape(-1, 3)
    tris = outward(pts, nodes[0].reshape(-1, 3).astype(np.int64) - 1, np.zeros(3))
    r = np.linalg.norm(LISTENER)
    rows = []
    for ka in (0.1, 1.0, 3.0):
        k = ka / a
        p = bem_pressure(pts, tris, np.ones(len(tris)), k * C, LISTENER)
        exact = RHO * C * k * a**2 * (k * C) / ((1 + ka**2) ** 0.5 * r)
        rows.append((ka, abs(p) / exact))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cells", type=int, nargs=3, default=[60, 6, 2])
    ap.add_argument("--up-to", type=float, default=10000.0, help="modes below this frequency [Hz]")
    ap.add_argument("--write", action="store_true")
    args = ap.parse_args()
    sys.path.insert(0, str(ROOT))
    import tomllib
    import fem_forms as ff
    from fem_forms.analyses.modal import solve_modal
    from fem_forms.output.fields import boundary_surface
    from fem_forms.output.radiation import Radiation
    ff.quiet_jit()

    sphere = sphere_check(0.02)
    d = tomllib.loads((ROOT / "demos" / "scenes" / "struck_bar.toml").read_text())
    d.pop("sound")
    d["mesh"]["cells"] = args.cells
    d["modal"]["up_to"] = args.up_to
    res = solve_modal(ff.Scene.from_dict(d))
    radiation = Radiation(res.model.V, LISTENER, RHO, C)
    lines = ["| mode | f [Hz] | ka (a = half length) | simple source [Pa] | BEM [Pa] | simple source / BEM [dB] "
             "| simple source [s] | BEM [s] |", "|---:|---:|---:|---:|---:|---:|---:|---:|"]
    ours_t, bem_t, diffs = [], [], []
    for i, (mode, f) in enumerate(zip(res.modes, res.frequencies_hz)):
        omega = 2 * math.pi * f
        t0 = time.perf_counter()
        ours = abs(radiation.pressure(mode, omega))
        ours_t.append(time.perf_counter() - t0)
        pts, tris, disp = boundary_surface(mode)
        tris = outward(pts, tris, 0.5 * (pts.min(axis=0) + pts.max(axis=0)))
        a, b, c = (pts[tris[:, j]] for j in range(3))
        n = np.cross(b - a, c - a)
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        un = np.einsum("ij,ij->i", disp[tris].mean(axis=1), n)
        t0 = time.perf_counter()
        bem = abs(bem_pressure(pts, tris, un, omega, LISTENER))
        bem_t.append(time.perf_counter() - t0)
        db = 20 * math.log10(ours / bem)
        diffs.append(db)
        ka = omega / C * 0.15
        lines.append(f"| {i + 1} | {f:.0f} | {ka:.2f} | {ours:.3e} | {bem:.3e} | {db:+.1f} | {ours_t[-1]:.3f} | "
                     f"{bem_t[-1]:.1f} |")
        print(lines[-1], flush=True)
    text = ("Sphere check (BEM on a gmsh sphere, h = a/5, against the pulsating sphere's closed form): "
            + ", ".join(f"ka = {ka}: |p_bem / p_exact| = {q:.4f}" for ka, q in sphere) + ".\n\n"
            f"Struck bar on {' x '.join(map(str, args.cells))} P2 cells ({res.model.dofs:,} dofs; "
            f"{len(tris):,} boundary triangles, {1000 * d['mesh']['size'][0] / args.cells[0]:.0f} mm cells along the bar), listener "
            f"{LISTENER.tolist()}, the {len(res.modes)} modes below {args.up_to:.0f} Hz:\n\n"
            + "\n".join(lines) + f"\n\nMedian |simple source / BEM|: {np.median(np.abs(diffs)):.1f} dB; largest "
            f"{np.max(np.abs(diffs)):.1f} dB. Time per mode (median): simple source {np.median(ours_t):.3f} s, "
            f"BEM {np.median(bem_t):.1f} s.\n")
    print(text)
    if args.write:
        (HERE / "radiation_bem.md").write_text(
            "# Radiated pressure: the simple-source integral against a boundary element solve\n\n"
            "Produced by `benchmarks/radiation_bem.py` (serial; bempp-cl 0.4.2 with numba, not a project "
            "dependency).\n\n" + text)


if __name__ == "__main__":
    main()
