"""Causal short-time spectra: the frames both twins of the detector see, computed one way.

Frame ``t`` of a signal holds the ``size`` samples that *end* at sample ``(t + 1) * hop``
(zeros before the signal starts), so a frame never looks ahead of the sample that closes it:
a hit enters a frame as soon as its first sample is played. Both the offline function and the
online class compute their frames through :func:`frames_at` on batches of frame ends; numpy's
FFT transforms every row of a batch the same way whatever the batch size, so the two twins see
bit-identical spectra.

Two spectra per frame: a short one (:data:`FLUX_SIZE` samples, 5.3 ms at 48 kHz) for the onset
function, where a short window keeps the attack's peak close to the attack, and a long one
(:data:`CLASS_SIZE`, 21 ms) summed into :data:`N_BANDS` log-spaced bands for classifying, where
a kick needs its low bins. Limit: the hop and sizes are in samples, chosen for 48 kHz; at
44.1 kHz they are 9 % longer in time.
"""

from __future__ import annotations

from functools import cache

import numpy as np

HOP = 128  # 2.67 ms at 48 kHz
FLUX_SIZE = 256
CLASS_SIZE = 1024
N_BANDS = 28
FLUX_BANDS = 20
LOG_GAIN = 100.0  # magnitude scale inside the log (full-scale float audio)
FLUX_LO_HZ = 300.0  # below, a short window sees a kick's fundamental beat with its phase
BAND_LO_HZ, BAND_HI_HZ = 35.0, 16_000.0


@cache
def hann(size: int) -> np.ndarray:
    return np.hanning(size + 2)[1:-1].astype(np.float64)


@cache
def band_edges(sr: int) -> np.ndarray:
    """Bin edges of the classification bands of a :data:`CLASS_SIZE` FFT at ``sr`` (each band
    at least one bin wide; log-spaced where the bins allow)."""
    nyq_bin = CLASS_SIZE // 2
    hz = np.geomspace(BAND_LO_HZ, min(BAND_HI_HZ, 0.45 * sr), N_BANDS + 1)
    edges = np.round(hz * CLASS_SIZE / sr).astype(np.int64)
    edges = np.clip(edges, 1, nyq_bin)
    for i in range(1, len(edges)):  # widen to one bin: the low bands are bins themselves
        edges[i] = max(edges[i], edges[i - 1] + 1)
    return edges


def frames_at(signal: np.ndarray, ends: np.ndarray, size: int) -> np.ndarray:
    """Magnitude spectra (len(ends), size // 2 + 1) of the Hann-windowed ``size`` samples
    ending at each index of ``ends`` (indices into ``signal``; each ≥ ``size``)."""
    idx = ends[:, None] - size + np.arange(size)[None, :]
    return np.abs(np.fft.rfft(signal[idx] * hann(size), axis=1))


def bands(spectra: np.ndarray, sr: int) -> np.ndarray:
    """Classification spectra summed into bands: (frames, N_BANDS)."""
    edges = band_edges(sr)
    csum = np.concatenate([np.zeros((spectra.shape[0], 1)), np.cumsum(spectra, axis=1)], axis=1)
    out: np.ndarray = csum[:, edges[1:]] - csum[:, edges[:-1]]
    return out


@cache
def flux_edges(sr: int) -> np.ndarray:
    """Bin edges of the onset function's bands on a :data:`FLUX_SIZE` FFT: log-spaced from
    :data:`FLUX_LO_HZ`, at least one bin each (the low ones are single bins)."""
    hz = np.geomspace(FLUX_LO_HZ, min(BAND_HI_HZ, 0.45 * sr), FLUX_BANDS + 1)
    edges = np.clip(np.round(hz * FLUX_SIZE / sr).astype(np.int64), 0, FLUX_SIZE // 2)
    for i in range(1, len(edges)):
        edges[i] = max(edges[i], edges[i - 1] + 1)
    return edges


def log_flux_spectra(spectra: np.ndarray, sr: int) -> np.ndarray:
    """Short spectra averaged into log-spaced bands and log-compressed (the onset function's
    input): averaging the many high bins of a cymbal's noisy decay keeps its frame-to-frame
    wobble from looking like new hits."""
    edges = flux_edges(sr)
    csum = np.concatenate([np.zeros((spectra.shape[0], 1)), np.cumsum(spectra, axis=1)], axis=1)
    mean = (csum[:, edges[1:]] - csum[:, edges[:-1]]) / np.diff(edges)
    out: np.ndarray = np.log10(1.0 + LOG_GAIN * mean)
    return out


def superflux(log_now: np.ndarray, log_before: np.ndarray) -> np.ndarray:
    """SuperFlux: the rise of each bin over the maximum of its three neighbours in an earlier
    frame (vibrato and a ringing cymbal's wobble do not count as rises), summed per frame."""
    widened = log_before.copy()  # each bin's max with its neighbours (the edges: their one)
    np.maximum(widened[:, 1:], log_before[:, :-1], out=widened[:, 1:])
    np.maximum(widened[:, :-1], log_before[:, 1:], out=widened[:, :-1])
    out: np.ndarray = np.maximum(log_now - widened, 0.0).sum(axis=1)
    return out
