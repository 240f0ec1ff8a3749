"""Modal sound: the ring of a struck solid as a sum of damped sinusoids, one per mode.

A unit impulse at point p along direction d excites mode i (mass-normalised phi_i) with modal
velocity phi_i(p).d, so its modal coordinate rings as (phi_i(p).d / omega_d,i) exp(-zeta_i omega_i t)
sin(omega_d,i t). Without a listener we hear the struck point's motion along d, which multiplies each
term by phi_i(p).d once more. With `listener`, each mode's displacement amplitude field
(phi_i(p).d / omega_d,i) phi_i radiates the pressure P_i at the listener (output/radiation.py), heard as
|P_i| exp(-zeta_i omega_i t) sin(omega_d,i t + arg P_i): a mode that moves the air little is quiet.
Both are products of two factors linear in phi_i, so independent of eigenvector signs (and, summed
over a repeated eigenvalue, of the basis the solver picked): serial and MPI runs write the same WAV.
Damping is Rayleigh's, zeta_i = alpha / (2 omega_i) + beta omega_i / 2, or interpolated in a table of
(frequency, zeta) pairs.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from fem_forms.output import probes
from fem_forms.output.radiation import Radiation
from fem_forms.scene import SoundSpec

PEAK_FLOOR_DB = -60.0        # spectrum peaks reported down to this level below the strongest
PEAK_PROMINENCE_DB = 6.0


def rayleigh_damping(omega: np.ndarray, alpha: float, beta: float) -> np.ndarray:
    """Modal damping ratio of Rayleigh damping C = alpha M + beta K."""
    return alpha / (2.0 * omega) + beta * omega / 2.0


def table_damping(freqs_hz: np.ndarray, pairs: list) -> np.ndarray:
    """Damping ratio per mode, linear in frequency between the [f, zeta] pairs, constant beyond them."""
    f, zeta = np.asarray(pairs, dtype=float).T
    return np.interp(freqs_hz, f, zeta)


def synthesize(freqs_hz: np.ndarray, amplitudes: np.ndarray, zetas: np.ndarray, duration: float,
               sample_rate: int, phases: np.ndarray | None = None) -> np.ndarray:
    """Sum of a_i exp(-zeta_i omega_i t) sin(omega_d,i t + phase_i), omega_i = 2 pi f_i (undamped)."""
    t = np.arange(int(round(duration * sample_rate))) / sample_rate
    signal = np.zeros_like(t)
    phases = np.zeros(len(freqs_hz)) if phases is None else phases
    for f, a, z, ph in zip(freqs_hz, amplitudes, zetas, phases):
        w = 2 * math.pi * f
        signal += a * np.exp(-z * w * t) * np.sin(w * math.sqrt(1.0 - z * z) * t + ph)
    return signal


def write_wav(path: Path, signal: np.ndarray, sample_rate: int) -> None:
    """16-bit mono PCM, scaled so the loudest sample is at 90 % of full scale (no clipping)."""
    from scipy.io import wavfile
    peak = float(np.abs(signal).max()) if signal.size else 0.0
    pcm = np.zeros(signal.shape, dtype=np.int16) if peak == 0 else \
        np.round(signal * (0.9 * 32767 / peak)).astype(np.int16)
    wavfile.write(str(path), sample_rate, pcm)


def spectrum_peaks(samples: np.ndarray, sample_rate: int, floor_db: float = PEAK_FLOOR_DB) -> list:
    """Frequencies [Hz] of the local maxima of the magnitude spectrum, refined by a parabola
    through the dB values. The window is the falling half of a Blackman-Harris window: a struck
    sound starts from silence and its short-lived high modes live at the start, which a symmetric
    window would erase; the taper at the end keeps slowly decaying modes from leaking."""
    from scipy.signal import find_peaks
    from scipy.signal.windows import blackmanharris
    x = np.asarray(samples, dtype=np.float64)
    if x.size < 8 or not np.any(x):
        return []
    spec = np.abs(np.fft.rfft(x * blackmanharris(2 * x.size)[x.size:]))
    db = 20 * np.log10(np.maximum(spec / spec.max(), 1e-15))
    idx, _ = find_peaks(db, height=floor_db, prominence=PEAK_PROMINENCE_DB)
    df = sample_rate / x.size
    peaks = []
    for i in idx:
        if 0 < i < len(db) - 1:
            a, b, c = db[i - 1], db[i], db[i + 1]
            den = a - 2 * b + c
            peaks.append((i + (0.5 * (a - c) / den if den != 0 else 0.0)) * df)
    return peaks


def read_wav(path: Path) -> tuple[int, np.ndarray]:
    from scipy.io import wavfile
    rate, data = wavfile.read(str(path))
    return rate, data.astype(np.float64)


def spectrogram_png(path: Path, samples: np.ndarray, sample_rate: int, freqs_hz, title: str) -> None:
    """Spectrogram (matplotlib specgram) with the computed modal frequencies marked at the right."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 5))
    # window long enough to resolve the lowest mode (8 bins below it), short enough for 16 columns
    f_low = min(freqs_hz) if len(freqs_hz) else 100.0
    nfft = 2 ** math.ceil(math.log2(max(256, 8 * sample_rate / f_low)))
    nfft = max(16, min(nfft, 2 ** int(math.log2(max(len(samples) // 16, 16)))))
    cmap = plt.get_cmap("magma").copy()
    cmap.set_bad(cmap(0.0))                         # a silent stretch (-inf dB) is drawn as the floor
    with np.errstate(divide="ignore"):
        _, _, _, image = ax.specgram(samples, NFFT=nfft, Fs=sample_rate, noverlap=3 * nfft // 4,
                                     cmap=cmap, scale="dB")
    top_db = float(np.nanmax(image.get_array()))
    image.set_clim(top_db - 90, top_db)              # 90 dB of dynamic range
    fig.colorbar(image, ax=ax, label="dB", pad=0.08)
    top = min(sample_rate / 2, 1.25 * max(freqs_hz)) if len(freqs_hz) else sample_rate / 2
    ax.set_ylim(0, top)
    for f in freqs_hz:
        ax.annotate("", xy=(1.0, f), xycoords=("axes fraction", "data"), xytext=(1.03, f),
                    textcoords=("axes fraction", "data"), arrowprops={"arrowstyle": "->", "color": "k"})
    ax.set_xlabel("time [s]")
    ax.set_ylabel("frequency [Hz]")
    ax.set_title(f"{title}: spectrogram (arrows: computed modes)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def damping_ratios(f_hz: np.ndarray, spec: SoundSpec) -> np.ndarray:
    """zeta per mode from the table or Rayleigh's law; inf for modes that do not oscillate (f <= 0)."""
    omega = 2 * math.pi * np.maximum(f_hz, 0.0)
    ok = omega > 0
    safe = np.where(ok, omega, 1.0)
    zeta = table_damping(safe / (2 * math.pi), spec.modal_damping) if spec.modal_damping is not None else \
        rayleigh_damping(safe, spec.alpha, spec.beta)
    return np.where(ok, zeta, np.inf)


def modal_sound(result, spec: SoundSpec, out: Path) -> dict:
    """Strike the modes of a ModalResult, write sound.wav and spectrogram.png (rank 0) and return
    the results.json entry, with the peaks measured from the written WAV's spectrum."""
    comm = result.model.mesh.comm
    proj = np.array([np.dot(probes.evaluate(f, {"strike": spec.point})["strike"], spec.direction)
                     for f in result.modes])                         # collective, all ranks agree
    f_hz = result.frequencies_hz
    omega = 2 * math.pi * np.maximum(f_hz, 0.0)
    zeta = damping_ratios(f_hz, spec)
    audible = (f_hz > 0) & (f_hz < spec.sample_rate / 2) & (zeta < 1.0)   # oscillating, below Nyquist
    omega_d = omega * np.sqrt(np.maximum(1.0 - zeta**2, 0.0))
    a = np.where(audible, proj / np.where(audible, omega_d, 1.0), 0.0)    # modal displacement amplitude
    if spec.listener is None:
        amps, phases = a * proj, np.zeros_like(a)
    else:
        radiation = Radiation(result.model.V, spec.listener, spec.air_density, spec.speed_of_sound)
        p = np.array([a[i] * radiation.pressure(mode, omega[i]) if audible[i] else 0.0
                      for i, mode in enumerate(result.modes)])        # collective
        amps, phases = np.abs(p), np.angle(p)
    entry = {"wav": "sound.wav", "spectrogram": "spectrogram.png", "peaks_hz": [],
             "modes_used": int(np.count_nonzero(audible & (amps > 0))),
             "heard": "strike point motion [m]" if spec.listener is None else "pressure at the listener [Pa]",
             "modal_amplitudes": amps.tolist(), "damping_ratios": np.where(audible, zeta, np.nan).tolist(),
             "strike": {"point": spec.point, "direction": spec.direction},
             "sample_rate": spec.sample_rate, "duration_s": spec.duration}
    if spec.listener is not None:
        entry["listener"] = {"point": spec.listener, "air_density": spec.air_density,
                             "speed_of_sound": spec.speed_of_sound, "phases_rad": phases.tolist()}
    if comm.rank == 0:
        signal = synthesize(f_hz[audible], amps[audible], zeta[audible], spec.duration, spec.sample_rate,
                            phases[audible])
        write_wav(out / "sound.wav", signal, spec.sample_rate)
        rate, pcm = read_wav(out / "sound.wav")
        entry["peaks_hz"] = spectrum_peaks(pcm, rate)
        spectrogram_png(out / "spectrogram.png", pcm, rate, f_hz[audible], result.model.scene.title)
    entry["peaks_hz"] = comm.bcast(entry["peaks_hz"], root=0)
    return entry
