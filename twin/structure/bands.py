"""Third-octave band energies of a sampled signal (the engines' agreement on the flexible structure's spectra).

Base-10 third-octave bands (IEC 61260 nominal): centre frequencies f_c = 10^(n/10) Hz, edges f_c · 10^(±1/20).
A band's energy is the sum of the Hann-windowed one-sided power spectrum over the FFT bins whose frequency lies in
[lower edge, upper edge). Engine-free (numpy).
"""

from __future__ import annotations

import numpy as np


def third_octave_centres(f_lo: float = 100.0, f_hi: float = 10000.0) -> np.ndarray:
    """Nominal-exact centre frequencies 10^(n/10) [Hz] from ``f_lo`` to ``f_hi`` (inclusive)."""
    n0, n1 = int(round(10 * np.log10(f_lo))), int(round(10 * np.log10(f_hi)))
    return 10.0 ** (np.arange(n0, n1 + 1) / 10.0)


def band_energies(x: np.ndarray, rate_hz: float, centres: np.ndarray | None = None) -> np.ndarray:
    """Band sums of the Hann-windowed periodogram ``|X_k|² / rate_hz`` of ``x`` (mean removed) in each
    third-octave band of ``centres`` [signal unit² s per sample]: ``len(x) / 2`` times the band's energy, so
    compare only signals of the same length and rate (as :func:`band_difference_db` does)."""
    centres = third_octave_centres() if centres is None else np.asarray(centres, dtype=float)
    x = np.asarray(x, dtype=np.float64)
    x = (x - x.mean()) * np.hanning(len(x))
    p = np.abs(np.fft.rfft(x)) ** 2 / rate_hz
    f = np.fft.rfftfreq(len(x), 1.0 / rate_hz)
    lo, hi = centres * 10 ** (-1 / 20), centres * 10 ** (1 / 20)
    return np.array([p[(f >= a) & (f < b)].sum() for a, b in zip(lo, hi)])


def band_difference_db(a: np.ndarray, b: np.ndarray, rate_hz: float, centres: np.ndarray | None = None) -> np.ndarray:
    """10 log10 of the band energies of ``a`` over those of ``b``, per band [dB]."""
    ea, eb = band_energies(a, rate_hz, centres), band_energies(b, rate_hz, centres)
    return 10.0 * np.log10(ea / eb)
