"""[sound.impact]: the sound of the contacts of a dynamic run.

Every accepted step records the force the named obstacle exerts on each surface node (the contact term's nodal
forces, barrier and friction). After the run the free part's modes about its rest shape (the modal analysis's
machinery on the same mesh: supports kept, loads, contact and other fields left out; a part without supports has
six rigid-body modes near 0 Hz, split off by the modal solve, and modes below HEARING_FLOOR_HZ are not heard)
take the modal forces phi_i . f(t), ring as damped oscillators at the audio rate (output/impact_sound.py) and
are heard at the `listener` (radiated pressure) or, without one, as the motion of the contact patch along the
impulse (each node weighted by its share of the impulse). impact.wav and its spectrogram are written by rank 0.
A run continued with --restart hears the contacts from t = 0: the checkpoint carries the recorded forces.
"""
from __future__ import annotations

from dataclasses import replace
import math
from pathlib import Path

from mpi4py import MPI
import numpy as np

from fem_forms.errors import InputError, SolveError
from fem_forms.model import build_model
from fem_forms.analyses.modal import solve_modal
from fem_forms.output import impact_sound, sound
from fem_forms.output.radiation import Radiation, check_listener
from fem_forms.scene.analyses.modal import ModalSpec

HEARING_FLOOR_HZ = 20.0          # modes below are not synthesised: inaudible (and rigid-body leftovers)
WAV, PICTURE = "impact.wav", "impact_spectrogram.png"


class ImpactRecorder:
    """on_step(system, t): the named obstacle's force on each surface node at every accepted step."""

    def __init__(self, spec):
        self.spec = spec
        self.surface = None
        self.times, self.nodes, self.forces = [], [], []

    def __call__(self, system, t: float) -> None:
        got = system.model.terms.surface_forces(self.spec.obstacle, system.u.vector)   # the same on every rank
        if got is None:
            raise InputError(f"sound.impact.obstacle = {self.spec.obstacle!r}: no such obstacle in [contact]")
        act, force, self.surface = got
        if len(self.times) == 0 and self.spec.listener is not None:
            check_listener(system.model.u, self.spec.listener)
        self.times.append(float(t))
        self.nodes.append(np.asarray(act).copy())
        self.forces.append(np.asarray(force).reshape(-1, 3).copy())

    def saved(self) -> dict[str, np.ndarray]:
        """Its history as flat arrays (a checkpoint's): times, each step's node count, nodes, forces."""
        counts = np.array([len(n) for n in self.nodes], dtype=np.int64)
        return {"times": np.asarray(self.times, dtype=float), "counts": counts,
                "nodes": np.concatenate(self.nodes) if self.nodes else np.zeros(0, np.int64),
                "forces": np.concatenate(self.forces) if self.forces else np.zeros((0, 3))}

    def restore(self, data: dict) -> None:
        """The history of `saved()`: a restarted run's sound covers the impact from t = 0."""
        cut = np.cumsum(data["counts"])[:-1]
        self.times = [float(t) for t in data["times"]]
        self.nodes = list(np.split(data["nodes"], cut)) if len(self.times) else []
        self.forces = list(np.split(data["forces"].reshape(-1, 3), cut)) if len(self.times) else []

    def totals(self) -> np.ndarray:
        """(steps, 3) the obstacle's total force on the part at each recorded step."""
        return np.array([f.sum(axis=0) for f in self.forces]).reshape(-1, 3)

    def impulses(self) -> np.ndarray:
        """(surface nodes, 3) each node's impulse, by the trapezoidal rule over the recorded steps."""
        J = np.zeros((self.surface.size, 3))
        t = np.asarray(self.times)
        w = np.zeros(len(t))
        if len(t) > 1:
            dt = np.diff(t)
            w[:-1] += dt / 2
            w[1:] += dt / 2
        for wk, act, f in zip(w, self.nodes, self.forces):
            np.add.at(J, act, wk * f)
        return J


def free_modes(system, spec):
    """The part's modes about its rest shape on the run's own mesh (the same dof numbering)."""
    scene = system.scene
    modal = ModalSpec(count=spec.count) if spec.count is not None else ModalSpec(up_to=spec.up_to)
    mscene = replace(scene, analysis="modal", modal=modal, sound=None, contact=None, fracture=None, thermal=None)
    model = build_model(mscene, loaded=system.model.loaded)
    same = np.array_equal(model.V.tabulate_dof_coordinates(), system.model.V.tabulate_dof_coordinates())
    if not model.mesh.comm.allreduce(same, op=MPI.LAND):       # every rank raises, or none (cannot happen)
        raise SolveError("impact sound: the modal space's dofs differ from the run's")
    try:
        return solve_modal(mscene, model=model)
    except InputError as e:               # e.g. more modes below up_to than the solver keeps: known only now
        raise SolveError(f"impact sound: [sound] up_to / count: {e}") from None


def impact_entry(result, recorder: ImpactRecorder, spec, out: Path) -> dict:
    """Modes, modal forces, the oscillators, impact.wav and its spectrogram (rank 0); the results.json entry."""
    system = result.system
    comm = system.model.mesh.comm
    modal = free_modes(system, spec)
    f_hz = modal.frequencies_hz
    omega = 2 * math.pi * np.maximum(f_hz, 0.0)
    zeta = sound.damping_ratios(f_hz, spec)
    keep = np.flatnonzero((f_hz >= HEARING_FLOOR_HZ) & (f_hz < spec.sample_rate / 2) & (zeta < 1.0))
    if recorder.surface is None:            # a restart that accepted no step: the surface from the contact term
        recorder.surface = system.model.terms.surface_forces(spec.obstacle, system.u.vector)[2]
    surface = recorder.surface
    pos = np.full(surface.size, -1)
    pos[surface.owned] = np.arange(len(surface.owned))
    modes = [modal.modes[i] for i in keep]
    phi = np.zeros((len(modes), len(surface.owned), 3))      # the modes at the surface nodes this rank owns
    for i, m in enumerate(modes):
        phi[i] = m.x.array.reshape(-1, 3)[surface.owned_local]
    # modal forces phi_i . f at each step: each rank sums its own surface nodes, then all ranks add up
    g = np.zeros((len(recorder.times), len(modes)))
    for s, (act, f) in enumerate(zip(recorder.nodes, recorder.forces)):
        mine = pos[act] >= 0
        g[s] = np.einsum("mnk,nk->m", phi[:, pos[act[mine]]], f[mine])
    g = comm.allreduce(g, op=MPI.SUM)
    J = recorder.impulses()
    net = J.sum(axis=0)
    direction = net / max(np.linalg.norm(net), 1e-300)
    share = np.linalg.norm(J, axis=1)
    share = share / max(share.sum(), 1e-300)
    if spec.listener is None:                 # the contact patch's motion along the impulse
        local = np.einsum("mnk,k,n->m", phi, direction, share[surface.owned])
        weights = comm.allreduce(local, op=MPI.SUM)
        heard = "contact patch motion along the impulse [m]"
    else:
        radiation = Radiation(modal.model.V, spec.listener, spec.air_density, spec.speed_of_sound)
        weights = np.array([radiation.pressure(m, omega[i]) for m, i in zip(modes, keep)])   # collective
        heard = "pressure at the listener [Pa]"
    entry = {"wav": WAV, "spectrogram": PICTURE, "obstacle": spec.obstacle, "heard": heard,
             "modes_used": len(keep), "frequencies_hz": f_hz[keep].tolist(), "damping_ratios": zeta[keep].tolist(),
             "modes_computed": len(f_hz), "rigid_modes": modal.rigid_modes,
             "peak_modal_force": np.abs(g).max(axis=0).tolist() if len(keep) else [],
             "sample_rate": spec.sample_rate, "duration_s": spec.duration, "peaks_hz": [],
             "modal_wall_time_s": modal.wall_time_s,
             **impact_sound.contact_history(np.asarray(recorder.times), recorder.totals())}
    if modal.band is not None:
        entry["modes_below_limit"] = modal.band.summary(modal.rigid_modes)["modes_below_limit"]
        entry["up_to_hz"] = spec.up_to
    if spec.listener is not None:
        entry["listener"] = {"point": spec.listener, "air_density": spec.air_density,
                             "speed_of_sound": spec.speed_of_sound}
    failed = None
    if comm.rank == 0:                            # a failure here is every rank's (never rank 0's alone)
        try:
            _synthesize(recorder, g, omega[keep], zeta[keep], weights, spec, out, entry, f_hz[keep],
                        system.scene.title)
        except Exception as e:                    # noqa: BLE001 (the run's caller turns it into one warning)
            failed = f"{type(e).__name__}: {(str(e).strip().splitlines() or [''])[0]}"
    failed, entry["peaks_hz"] = comm.bcast((failed, entry["peaks_hz"]), root=0)
    if failed:
        raise SolveError(f"impact sound: {failed}")
    return entry


def _synthesize(recorder: ImpactRecorder, g: np.ndarray, omega: np.ndarray, zeta: np.ndarray, weights: np.ndarray,
                spec, out: Path, entry: dict, f_hz: np.ndarray, title: str) -> None:
    """On rank 0: the oscillators at the audio rate, impact.wav, its spectrum peaks and spectrogram."""
    t = np.asarray(recorder.times)                # the sound starts at the first recorded step (a --restart's)
    q, v = impact_sound.modal_response(t - t[0], g, omega, zeta, spec.duration, spec.sample_rate)
    if spec.listener is not None and len(g):      # a force still held at the end bends the part statically:
        q = q - (g[-1] / omega**2)[:, None]       # that deflection radiates nothing (pressure needs motion)
    signal = impact_sound.heard(q, v, omega, weights)
    sound.write_wav(out / WAV, signal, spec.sample_rate)
    rate, pcm = sound.read_wav(out / WAV)
    entry["peaks_hz"] = sound.spectrum_peaks(pcm, rate)
    sound.spectrogram_png(out / PICTURE, pcm, rate, f_hz, f"{title}: impact")
