"""The records of a measurement campaign: a measured record and an outcome record, each read from its CSV file.

A record file has the columns ``time`` [s], ``ground_acc`` [m/s^2] and
``theta`` [rad], and optional extra measured channels ``ground_acc_<what>``
[m/s^2] (``ground_acc_vertical``: the vertical table acceleration), which the
record's motion carries in ``channels`` (see docs/reference/campaign-format.md).
A header cell may name another unit in brackets (``time [ms]``,
``ground_acc [g]``, ``theta [deg]``, see :func:`housner.motion.parse_unit`);
the reader converts once, to SI. A time column without a unit whose step is
outside 1e-5 .. 0.1 s is refused (milliseconds taken for seconds). A
ground-motion record without a theta column is an :class:`OutcomeRecord`: the
table motion and the observed outcome written in its ``[[record]]`` table.

A free-vibration record starts at the release: its initial angle is fitted
to the first samples (:func:`estimate_release`) and becomes the motion's
``theta0``. The campaign that holds the records, and its reader, are in
:mod:`housner.scenarios.campaigns.campaign`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from housner.errors import DataFileError
from housner.free_vibration.calibration import estimate_noise
from housner.free_vibration.impacts import noise_crossings
from housner.motion import GroundMotion
from housner.readers.measured_data import (
    CHANNEL_PREFIX,
    QUANTITIES,
    read_csv_header,
    read_csv_si,
    require_samples,
    uniform_step,
)
from housner.scenarios.campaigns.sensor_noise import WHITE, SensorNoise
from housner.specimen import Specimen

__all__ = [
    "KINDS",
    "OVERTURN_ANGLE",
    "CampaignRecord",
    "MeasuredRecord",
    "OutcomeRecord",
    "estimate_release",
    "read_record",
]

#: Record kinds of the format.
KINDS = ("free_vibration", "ground_motion")
#: A measured block has overturned once |theta| reaches this angle [rad]: it lies on its side at
#: pi/2; the 10 % margin allows for the sensor and for the block bouncing on the table.
OVERTURN_ANGLE = 0.9 * math.pi / 2
#: |theta| beyond pi/2 by more than this [rad] is not a rotation of a block on a table.
_THETA_SLACK = 0.1
#: The release fit of a free-vibration record uses the samples until the block has fallen by
#: this fraction of its initial angle [-]: there theta0 - theta(t) ~ c t^2 + d t^4 holds to the noise.
_RELEASE_DROP = 0.3
#: A free-vibration record must start at least this many noise sigmas away from rest [-].
_RELEASE_MIN_SIGMAS = 10.0


@dataclass(frozen=True, eq=False)
class CampaignRecord:
    """What every record of a campaign holds (:class:`MeasuredRecord`, :class:`OutcomeRecord`): the test, its file,
    its table motion and the ground motion it played.

    Attributes
    ----------
    id : str
        Record id from campaign.toml.
    kind : str
        One of :data:`KINDS` (an outcome record's is ``"ground_motion"``).
    file : pathlib.Path
        The CSV file.
    motion : GroundMotion
        The measured table acceleration [m/s^2] on the record's sample grid.
    group : str or None
        The ground motion the test played, from the record's ``group`` key: records that share a group were
        shaken by the same motion (one record at several scalings, say), so a held-out fold keeps them
        together. None: the record is a group of its own. A keyword-only field.
    """

    id: str
    kind: str
    file: Path
    motion: GroundMotion
    group: str | None = field(default=None, kw_only=True)

    @property
    def dt(self) -> float:
        """Sample step [s]."""
        return self.motion.dt


@dataclass(frozen=True, eq=False)
class MeasuredRecord(CampaignRecord):
    """One measured test: a :class:`CampaignRecord` with its theta history. A free-vibration record starts at the
    release: its motion's ``theta0`` is the measured initial angle [rad] and its ``theta_dot0`` 0.

    Attributes
    ----------
    t : ndarray
        Sample times [s], starting at 0 (at the release for a free-vibration
        record whose file starts with a hold; see ``t_offset``).
    theta : ndarray
        Measured rotation [rad] at ``t``.
    noise : float
        Standard deviation of the measurement noise on theta [rad], estimated
        from the record (:func:`housner.free_vibration.calibration.estimate_noise`).
    overturned : bool
        The block overturned: |theta| reached :data:`OVERTURN_ANGLE`, or the
        campaign says so (``overturned = true`` in the record's table).
    t_offset : float
        Time in the file of the first sample kept [s] (the release of a
        free-vibration record held before it; else the file's first time).
    hold : ndarray
        The theta samples of the hold before a free vibration's release [rad] (the block still at
        ``theta0``: a quiet part for the sensor's noise); empty when the record starts at the release.
    noise_model : SensorNoise
        The correlation in time of the sensor's noise (:mod:`housner.scenarios.campaigns.sensor_noise`):
        white until the campaign's sensor is assessed
        (:func:`housner.scenarios.diagnosis.sensor_assessment.assess_sensor`).
    valid : ndarray of bool or None
        Samples the sensor recorded truly (None: all). A sensor fault's samples (saturation, a spike, a
        dropout) are False: no error is taken on them.
    clip : tuple of float
        The sensor's range (low, high) [rad]: a saturating sensor reads no further (default unbounded).
    position : int
        The record's place among the campaign's ``[[record]]`` tables, the recording order, counting the
        records that could not be read (-1: not from a campaign file).
    """

    t: np.ndarray
    theta: np.ndarray
    noise: float
    overturned: bool
    t_offset: float = 0.0
    hold: np.ndarray = field(default_factory=lambda: np.zeros(0))
    noise_model: SensorNoise = WHITE
    valid: np.ndarray | None = None
    clip: tuple[float, float] = (-math.inf, math.inf)
    position: int = -1

    @property
    def theta_max(self) -> float:
        """Largest measured |theta| [rad] (pi/2 when overturned)."""
        return math.pi / 2 if self.overturned else float(np.max(np.abs(self.theta)))

    @property
    def is_free_vibration(self) -> bool:
        return self.kind == "free_vibration"

    @cached_property
    def impacts(self) -> np.ndarray:
        """Indices of the measured impacts (read-only), derived once per record: zero crossings of theta with a
        hysteresis of 4 noise sigmas (:func:`housner.free_vibration.impacts.noise_crossings`; for each, the first
        sample beyond
        the band on the new side). The error window of every comparison and every scorer counts them."""
        imp = noise_crossings(self.theta, self.noise)
        imp.flags.writeable = False
        return imp


@dataclass(frozen=True, eq=False)
class OutcomeRecord(CampaignRecord):
    """One test of which only the table motion and the outcome were measured (no theta channel): a
    :class:`CampaignRecord` with its outcome.

    Attributes
    ----------
    overturned : bool
        The observed outcome.
    theta_max : float or None
        Measured largest |theta| [rad], where it was measured.
    residual_displacement : float or None
        Measured residual displacement of the block [m], where measured.
    pgv_measured : float or None
        The measured peak table velocity [m/s] (from a displacement channel), where given.
    """

    overturned: bool
    theta_max: float | None = None
    residual_displacement: float | None = None
    pgv_measured: float | None = None

    @property
    def pga(self) -> float:
        """Peak table acceleration [m/s^2]."""
        return float(np.max(np.abs(self.motion.acc)))

    @cached_property
    def pgv(self) -> float:
        """Peak table velocity [m/s]: the measured one where given, else the acceleration integrated after a
        high-pass (:meth:`housner.GroundMotion.pgv`)."""
        return self.pgv_measured if self.pgv_measured is not None else self.motion.pgv()


def estimate_release(t, theta, noise: float) -> tuple[int, float]:
    """Release sample and initial angle of a free-vibration record, robust to noise.

    The block is at rest at theta0 (possibly held for a while) and falls
    freely from the release on; near the release
    theta(t) = theta0 + c tau^2 + d tau^4 with tau = max(t - t_r, 0) (the
    cubic term vanishes because theta' = 0 at the release). The model is
    fitted by least squares over the samples until the block has fallen by
    30 % of its angle, profiling the release time t_r over the samples; a
    hold (t_r > 0) is accepted only when it lowers the squared residual by
    more than ln(n) noise^2 (the Bayesian information criterion's price of
    one more parameter).

    Parameters
    ----------
    t : array_like
        Uniform sample times [s].
    theta : array_like
        Measured rotation [rad].
    noise : float
        Noise standard deviation [rad].

    Returns
    -------
    k_release : int
        Index of the sample nearest the release (0 when the record starts at it).
    theta0 : float
        Fitted angle at that sample [rad]; its standard error is about
        2 noise / sqrt(samples in the fit) (0.1-0.2 mrad at 500 Hz and 0.8 mrad).

    Raises
    ------
    ValueError
        The record does not start away from rest (|theta0| below 10 noise
        sigmas) or never falls.
    """
    t = np.asarray(t, dtype=float)
    th = np.asarray(theta, dtype=float)
    k0 = min(th.size, 9)
    start = float(np.median(th[:k0]))
    sigma = max(float(noise), 1e-12)
    if abs(start) < _RELEASE_MIN_SIGMAS * sigma:
        raise ValueError(
            f"a free-vibration record must start from a released tilt: the first samples are at "
            f"{start:.3g} rad, within {_RELEASE_MIN_SIGMAS:g} noise sigmas ({sigma:.2g} rad) of rest"
        )
    s = math.copysign(1.0, start)
    fallen = np.flatnonzero(s * (start - th) > _RELEASE_DROP * abs(start))
    if fallen.size == 0:
        far = float(np.max(s * th))
        if far > abs(start) + _RELEASE_DROP * abs(start):
            raise ValueError(
                f"the free-vibration record never rocks back toward rest: theta moves away from its release "
                f"at {start:.4g} rad to {s * far:.4g} rad (the block toppled; a release beyond the overturning "
                f"angle cannot calibrate p or r)"
            )
        raise ValueError("the free-vibration record never falls from its initial tilt")
    kw = int(fallen[0])
    # candidate releases: every sample up to where the record has clearly left the plateau
    left = np.flatnonzero(s * (start - th[:kw]) > 4.0 * sigma)
    k_hi = int(left[0]) if left.size else kw
    cands = np.arange(0, max(k_hi, 1))
    if cands.size > 400:
        cands = cands[-400:]
    y = th[: kw + 1]
    tt = t[: kw + 1]
    fits = []
    for kr in cands:
        tau = np.maximum(tt - t[kr], 0.0) / max(tt[-1] - t[kr], 1e-12)
        A = np.column_stack((np.ones_like(tau), tau**2, tau**4))
        coef, *_ = np.linalg.lstsq(A, y, rcond=None)
        fits.append((float(np.sum((y - A @ coef) ** 2)), int(kr), float(coef[0])))
    best = min(fits)
    at_start = fits[0] if fits[0][1] == 0 else best
    # A hold is one more parameter: accept it only when it lowers the residual by more than the
    # Bayesian-information price of a parameter, ln(n) sigma^2 (noise alone would not).
    if at_start[0] - best[0] <= math.log(y.size) * sigma * sigma:
        best = at_start
    return best[1], best[2]


def read_record(root: Path, rec: dict, specimen: Specimen) -> MeasuredRecord | OutcomeRecord:
    """Read one record of a campaign from its CSV file.

    Parameters
    ----------
    root : pathlib.Path
        The campaign folder; a relative ``file`` is resolved against it.
    rec : dict
        The record's ``[[record]]`` table, validated (``id``, ``kind``, ``file``, optional outcome keys and
        ``group``).
    specimen : Specimen
        The campaign's specimen (a free vibration released beyond its alpha is refused).

    Returns
    -------
    MeasuredRecord or OutcomeRecord
        An :class:`OutcomeRecord` for a ground-motion file without a theta column, else a
        :class:`MeasuredRecord` in SI (a free vibration starting at its release).

    Raises
    ------
    housner.errors.DataFileError
        The file is unreadable or malformed: the message names the file, line and column.
    """
    path = (root / rec["file"]).resolve() if not Path(rec["file"]).is_absolute() else Path(rec["file"])
    header = read_csv_header(path)
    if "theta" not in header and "ground_acc" in header and rec["kind"] == "ground_motion":
        return _read_outcome_record(path, rec)
    # optional extra channels: every column named ground_acc_<what> (e.g. ground_acc_vertical [m/s^2])
    extra = [c for c in dict.fromkeys(header) if c.startswith(CHANNEL_PREFIX)]
    quantities = {**QUANTITIES, **{c: "acceleration" for c in extra}}
    table = read_csv_si(path, quantities)  # converted to SI from the units in the header (none: SI)
    (t, acc, theta), lines = table.values[:3], table.lines
    channels = dict(zip(extra, table.values[3:], strict=True))
    dt = uniform_step(path, t, lines, "time", assumed_seconds=table.units[0] is None)
    bad = np.flatnonzero(np.abs(theta) > math.pi / 2 + _THETA_SLACK)
    if bad.size:
        k = int(bad[0])
        raise DataFileError(
            path,
            f"|theta| = {abs(theta[k]):.4g} rad is beyond pi/2: not a rotation in rad of a block on a table "
            "(degrees or another unit? write it in the header, e.g. `theta [deg]`)",
            line=int(lines[k]),
            column="theta",
        )
    require_samples(path, theta.size, line=int(lines[-1]))
    noise = estimate_noise(theta)
    overturned = bool(rec.get("overturned", False)) or bool(np.max(np.abs(theta)) >= OVERTURN_ANGLE)
    k_rel, theta0 = (
        _release(path, t, theta, noise, int(lines[0]), specimen) if rec["kind"] == "free_vibration" else (0, 0.0)
    )
    t_off = float(t[k_rel])
    theta_file = theta
    acc = acc[k_rel:]
    theta = theta[k_rel:]
    try:
        motion = GroundMotion(
            acc=acc,
            dt=dt,
            name=rec["id"],
            provenance=f"{path.name} (campaign record, {rec['kind']})",
            theta0=theta0,
            theta_dot0=0.0,
            channels={c: a[k_rel:] for c, a in channels.items()},
        )
    except ValueError as e:  # a channel name the format does not allow
        raise DataFileError(path, str(e), line=1) from None
    return MeasuredRecord(
        id=rec["id"],
        kind=rec["kind"],
        file=path,
        motion=motion,
        t=np.arange(theta.size) * dt,
        theta=theta,
        noise=noise,
        overturned=overturned,
        t_offset=t_off,
        hold=np.array(theta_file[:k_rel]),
        group=rec.get("group"),
    )


def _release(path: Path, t, theta, noise: float, line: int, specimen: Specimen) -> tuple[int, float]:
    """The release sample and initial angle [rad] of a free-vibration record (:func:`estimate_release`), refused
    with the file's first data ``line`` when the record does not start from a tilt or starts beyond alpha."""
    try:
        k_rel, theta0 = estimate_release(t, theta, noise)
    except ValueError as e:
        raise DataFileError(path, str(e), line=line, column="theta") from None
    if abs(theta0) >= specimen.alpha:
        raise DataFileError(
            path,
            f"released at theta0 = {theta0:.4g} rad, beyond alpha = {specimen.alpha:.4g} rad: the block "
            "would overturn without rocking",
            line=line,
            column="theta",
        )
    return k_rel, theta0


def _read_outcome_record(path: Path, rec: dict) -> OutcomeRecord:
    """A ground-motion record without a theta column: the table motion and the observed outcome."""
    if "overturned" not in rec:
        raise DataFileError(
            path,
            f"record {rec['id']!r} has no theta column and no outcome: write `overturned = true` or `false` in its "
            "[[record]] table (a record needs a measured theta or an observed outcome)",
            line=1,
        )
    table = read_csv_si(path, {"time": "time", "ground_acc": "acceleration"})
    (t, acc), lines = table.values[:2], table.lines
    dt = uniform_step(path, t, lines, "time", assumed_seconds=table.units[0] is None)
    require_samples(path, acc.size, line=int(lines[-1]))
    motion = GroundMotion(acc=acc, dt=dt, name=rec["id"], provenance=f"{path.name} (campaign outcome record)")
    return OutcomeRecord(
        id=rec["id"],
        kind=rec["kind"],
        file=path,
        motion=motion,
        overturned=bool(rec["overturned"]),
        theta_max=rec.get("theta_max"),
        residual_displacement=rec.get("residual_displacement"),
        pgv_measured=None if rec.get("pgv") is None else float(rec["pgv"]),
        group=rec.get("group"),
    )
