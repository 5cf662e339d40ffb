"""The theta sensor's noise as measured: its variance and its correlation in time.

Real rotation sensors do not give white noise, and an estimate from differences
(:func:`housner.free_vibration.calibration.estimate_noise`, exact for white noise) can be several times too small.
:class:`SensorNoise` is the noise of one campaign's theta channel, measured on the samples where the block
is known to be still (chosen by :mod:`housner.scenarios.diagnosis.sensor_assessment`): its standard
deviation, its autocorrelation, and whether it is distinguishable from white noise at all (a Ljung-Box
test, :data:`WHITE_LEVEL`, :data:`LB_LAGS`; :data:`WHITE` is the special case). It draws noise of the same
spectrum (:meth:`SensorNoise.draw`, circulant embedding) and counts effective samples
(:meth:`SensorNoise.mean_sd`). Why, and how the diagnosis uses it, are in ``docs/explanation/diagnosis.md``
("The sensor, first").

References
----------
Ljung, G. M., Box, G. E. P. (1978). On a measure of lack of fit in time series models. Biometrika 65(2).
Dietrich, C. R., Newsam, G. N. (1997). Fast and exact simulation of stationary Gaussian processes through
circulant embedding of the covariance matrix. SIAM J. Sci. Comput. 18(4).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from housner.free_vibration.calibration import estimate_noise

__all__ = [
    "LB_LAGS",
    "MIN_QUIET_SAMPLES",
    "WHITE",
    "WHITE_LEVEL",
    "WHITE_RATIO",
    "SensorNoise",
    "estimate_sensor_noise",
]

#: Lags of the Ljung-Box whiteness test [samples].
LB_LAGS = 20
#: Level of the whiteness test [-]: below it the noise is treated as correlated. Strict, because the
#: white special case keeps the independent-sample formulas that a correct white sensor deserves.
WHITE_LEVEL = 1e-3
#: Below this ratio of the noise's standard deviation to its difference-based estimate the noise is treated as
#: white whatever the test says [-]: the floor's mean depends on the variance alone, and a tenth more is within
#: what the floor's replicas resolve.
WHITE_RATIO = 1.1
#: Fewest quiet samples, all segments together, for the correlation to be measured [-].
MIN_QUIET_SAMPLES = 400
#: Longest lag of the autocorrelation [s], and at most this share of the longest quiet segment [-].
MAX_LAG_S = 2.0
MAX_LAG_SHARE = 0.5


@dataclass(frozen=True)
class SensorNoise:
    """Noise of a theta channel: standard deviation and autocorrelation.

    Attributes
    ----------
    sigma : float
        Standard deviation of the noise about the rest level [rad] (0: not measured).
    rho : ndarray
        Autocorrelation at lags 0 .. max_lag [-] (rho[0] = 1); ``[1.0]`` for white noise.
    white : bool
        True when the quiet samples do not tell the noise from white (or there are too few of them).
    dt : float
        Sample step the lags are counted in [s].
    n_samples : int
        Quiet samples measured [-].
    pvalue : float
        Ljung-Box p-value of whiteness [-] (NaN: not tested).
    diff_ratio : float
        sigma over the estimate from third differences on the same samples [-] (1 for white noise; 3 means a
        difference-based estimate is three times too small).
    sources : dict
        Where the quiet samples came from: source -> samples.
    """

    sigma: float = 0.0
    rho: np.ndarray = field(default_factory=lambda: np.ones(1))
    white: bool = True
    dt: float = 0.0
    n_samples: int = 0
    pvalue: float = math.nan
    diff_ratio: float = 1.0
    sources: dict = field(default_factory=dict)

    @property
    def max_lag(self) -> int:
        return int(self.rho.size - 1)

    @property
    def correlation_time(self) -> float:
        """Integral time scale dt (1/2 + sum_k rho_k), the sum stopped at the first lag where rho <= 0 [s]."""
        if self.white or self.rho.size < 2:
            return 0.5 * self.dt
        r = self.rho[1:]
        stop = np.flatnonzero(r <= 0)
        r = r[: int(stop[0])] if stop.size else r
        return float(self.dt * (0.5 + r.sum()))

    def mean_sd(self, sigma: float, m: int) -> float:
        """Standard deviation of the mean of ``m`` consecutive samples of noise of standard deviation ``sigma``."""
        m = max(int(m), 1)
        if self.white or m == 1:
            return float(sigma) / math.sqrt(m)
        k = np.arange(1, min(m, self.rho.size))
        s = 1.0 + 2.0 * float(np.sum((1.0 - k / m) * self.rho[k]))
        return float(sigma) * math.sqrt(max(s, 1.0 / m) / m) if s > 0 else float(sigma) / m

    def effective_samples(self, m: int) -> float:
        """Independent samples worth as much as ``m`` consecutive ones, for a mean [-] (m for white noise)."""
        sd = self.mean_sd(1.0, m)
        return 1.0 / (sd * sd)

    def draw(self, rng: np.random.Generator, sigma: float, n: int) -> np.ndarray:
        """``n`` samples of noise of standard deviation ``sigma`` with this autocorrelation [rad]."""
        if self.white or self.rho.size < 2:
            return rng.normal(0.0, sigma, n)
        lam = self._spectrum(n)
        m = lam.size
        z = rng.standard_normal(m) + 1j * rng.standard_normal(m)
        x = np.fft.fft(np.sqrt(lam / m) * z).real[:n]
        return float(sigma) * x

    def _spectrum(self, n: int) -> np.ndarray:
        # the circulant embedding of rho (zero beyond max_lag) on the next power of two >= 2 max(n, max_lag)
        m = 1 << int(math.ceil(math.log2(2 * max(n, self.rho.size))))
        key = m
        cache = self.__dict__.setdefault("_spectra", {})
        if key not in cache:
            c = np.zeros(m)
            c[: self.rho.size] = self.rho
            c[m - self.max_lag :] = self.rho[1:][::-1]
            lam = np.clip(np.fft.fft(c).real, 0.0, None)
            cache[key] = lam * (m / lam.sum())  # unit variance after clipping the few negative ordinates
        return cache[key]

    def to_dict(self) -> dict:
        return {
            "sigma": self.sigma,
            "white": self.white,
            "correlation_time": self.correlation_time,
            "diff_ratio": self.diff_ratio,
            "n_samples": self.n_samples,
            "pvalue": self.pvalue,
            "max_lag": self.max_lag,
            "rho_first": [float(v) for v in self.rho[:11]],
            "sources": dict(self.sources),
        }


#: White noise, nothing measured.
WHITE = SensorNoise()


def estimate_sensor_noise(segments: Sequence[tuple[str, np.ndarray]], dt: float, level: float = 0.0) -> SensorNoise:
    """Measure the noise on quiet segments (``docs/explanation/diagnosis.md``, "The sensor, first").

    Parameters
    ----------
    segments : sequence of (source, ndarray)
        theta [rad] where the block is still, each segment contiguous; ``source`` names where it came from.
    dt : float
        Sample step [s].
    level : float or sequence
        The rest level subtracted [rad]: one for all segments, or one per segment.

    Returns
    -------
    SensorNoise
        :data:`WHITE` with ``n_samples`` 0 when the segments hold fewer than :data:`MIN_QUIET_SAMPLES`.
    """
    levels = np.broadcast_to(np.asarray(level, dtype=float), (len(segments),))
    xs = [np.asarray(x, dtype=float) - lv for (_s, x), lv in zip(segments, levels, strict=True) if len(x) >= 8]
    n = int(sum(x.size for x in xs))
    sources: dict[str, int] = {}
    for s, x in segments:
        sources[s] = sources.get(s, 0) + len(x)
    if n < MIN_QUIET_SAMPLES:
        return SensorNoise(n_samples=0, dt=dt, sources=sources)
    var = float(sum(float(np.dot(x, x)) for x in xs) / n)
    sigma = math.sqrt(var)
    longest = max(x.size for x in xs)
    max_lag = int(max(min(MAX_LAG_S / dt, MAX_LAG_SHARE * longest), LB_LAGS))
    num = np.zeros(max_lag + 1)
    for x in xs:
        L = min(max_lag, x.size - 1)
        # every lag at once: the FFT autocorrelation of the zero-padded segment
        f = np.fft.rfft(x, 2 * x.size)
        ac = np.fft.irfft(f * np.conj(f))[: L + 1]
        num[: L + 1] += ac
    # the biased estimate (every lag over all n samples): a sum of each segment's positive semi-definite one,
    # so its spectrum is never negative (the unbiased one's can be, at long lags); its bias at lag k is the
    # share k / (segment length), a few per mille at the lags that matter
    gamma = num / n
    rho = gamma / gamma[0]
    # Ljung-Box on the pooled autocorrelation
    k = np.arange(1, LB_LAGS + 1)
    q = float(n * (n + 2) * np.sum(rho[k] ** 2 / np.maximum(n - k, 1)))
    pvalue = float(stats.chi2.sf(q, LB_LAGS))
    d_sig = float(np.median([estimate_noise(x) for x in xs if x.size >= 16]))
    ratio = sigma / d_sig if d_sig > 0 else math.inf
    if pvalue >= WHITE_LEVEL or ratio < WHITE_RATIO:
        return SensorNoise(sigma, np.ones(1), True, dt, n, pvalue, ratio, sources)
    # the autocorrelation is kept up to the last lag where it stands out of its own noise band (beyond,
    # pooled estimates only add sampling noise to the spectrum), under a Parzen lag window: its transform is
    # never negative, so neither is the spectrum of the drawn noise (a hum's autocorrelation does not decay,
    # and cutting it square would leave negative side lobes); at lag k of L it keeps 1 - 6 (k/L)^2 of short lags
    band = 2.0 / math.sqrt(n)
    above = np.flatnonzero(np.abs(rho) > band)
    last = int(min(max_lag, max(int(above[-1]) if above.size else 1, LB_LAGS)))
    u = np.arange(last + 1) / (last + 1)
    parzen = np.where(u <= 0.5, 1 - 6 * u**2 + 6 * u**3, 2 * (1 - u) ** 3)
    r = rho[: last + 1] * parzen
    return SensorNoise(sigma, r, False, dt, n, pvalue, ratio, sources)
