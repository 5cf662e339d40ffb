"""The records a diagnosis fits and judges on: the split into folds, and a model's errors on a set of records.

:func:`cv_folds` deals every record into one of K folds (the diagnosis'
cross-validation), :func:`split_records` makes the older single split, and
:class:`Scorer` runs the analytic engine on a fixed set of records (each cut
to its error window) and scores a list of effects by the time-history error
of :mod:`housner.scenarios.diagnosis.comparison.history_error` [alpha].

No score is made of a non-finite number: a model whose theta history is not finite on a record
is refused by name, with the record, before any score (:class:`NonFiniteHistory`), and a score
that comes out non-finite all the same stops with :class:`NonFiniteScore` (:func:`check_finite`).
Both are ``ValueError``: the model or the records handed in are at fault, and the same
command can only fail again.

:func:`decimated` makes the records the diagnosis' search runs on when a campaign is sampled far
above what the physics needs (:data:`SEARCH_RATE`): every q-th sample of theta (the sensor noise
stays white of the same sigma per sample, so a record's error is the same mean over fewer samples),
and the table acceleration, the model's input, through an anti-alias filter first.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np
from scipy import signal

from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.campaigns.campaign_records import MeasuredRecord
from housner.scenarios.diagnosis.comparison.history_error import ERROR_CLIP, error_window, scored_error
from housner.scenarios.diagnosis.comparison.record_comparison import release_sensitivities, simulate_records

__all__ = [
    "DEFAULT_FOLDS",
    "NonFiniteHistory",
    "NonFiniteScore",
    "SEARCH_RATE",
    "Scorer",
    "check_finite",
    "check_train_fraction",
    "cv_folds",
    "decimated",
    "model_text",
    "non_finite",
    "split_records",
]

#: The lowest sample rate the diagnosis' search decimates a campaign to [Hz]. The library's fit ranges
#: are set for it (:data:`housner.scenarios.diagnosis.selection.fitting.FIT_BOUNDS`: the fastest physics it fits,
#: a 100 Hz foundation, has 5 samples a period; an impact is instantaneous), and so are the seed
#: campaigns (500 Hz). A campaign sampled at q >= 2 times it is searched on every q-th sample.
SEARCH_RATE = 500.0
#: Fewest samples a decimated record keeps [-] (else the campaign is searched as it is).
_MIN_DECIMATED = 50
#: Cross-validation folds [-]: every record is held out once, so the answer rests on all of them
#: and depends far less on the assignment than one random split does.
DEFAULT_FOLDS = 5
#: What :func:`housner.engines.base.check_response` says of a response that is not finite (its message
#: reaches the scorer as text, through
# :func:`housner.scenarios.diagnosis.comparison.record_comparison.simulate_records`).
_NON_FINITE_MARKS = ("non-finite", "no theta_max")


class NonFiniteScore(ValueError):
    """A score, an error or a floor of the diagnosis is not finite (NaN or infinite); the message says which."""


class NonFiniteHistory(NonFiniteScore):
    """A model's theta history is not finite on a record: the model is refused before any score.

    Attributes
    ----------
    effects : tuple of str
        The names of the model's effects (empty: the plain Housner model).
    record : str
        The first record (in campaign order) on which the history is not finite.
    """

    def __init__(self, message: str, effects: Sequence[str] = (), record: str = ""):
        super().__init__(message)
        self.effects = tuple(effects)
        self.record = record


def model_text(effects: Sequence[Any]) -> str:
    """A model in words: "the plain Housner model" or "the model with restitution(r=0.9) + ..."."""
    if not effects:
        return "the plain Housner model"
    parts = []
    for e in effects:
        d = e.describe() if hasattr(e, "describe") else {"name": str(e)}
        args = ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in d.items() if k != "name")
        parts.append(f"{d['name']}({args})")
    return "the model with " + " + ".join(parts)


def check_finite(what: str, values, ids: Sequence[str] | None = None) -> None:
    """NonFiniteScore naming ``what`` (and the first record of ``ids`` concerned) unless every value is finite."""
    v = np.asarray(values, dtype=float)
    bad = np.flatnonzero(~np.isfinite(v))
    if bad.size:
        where = f" on record {ids[int(bad[0])]!r}" if ids is not None and bad[0] < len(ids) else ""
        raise NonFiniteScore(
            f"{what} is not finite ({v.flat[int(bad[0])]}){where}; the diagnosis stops rather than judge on it"
        )


def check_train_fraction(train_fraction) -> float:
    """``train_fraction`` as a float in (0, 1) [-]; ValueError otherwise."""
    tf = float(train_fraction)
    if not 0.0 < tf < 1.0:
        raise ValueError(f"`train_fraction` must lie in (0, 1), got {train_fraction!r}")
    return tf


def split_records(campaign: Campaign, train_fraction: float = 0.5, seed=0) -> tuple[list[str], list[str]]:
    """Training and held-out record ids: free vibration trains, ground motions are split at random.

    Parameters
    ----------
    campaign : Campaign
    train_fraction : float
        Share of the ground-motion records used for fitting [-], in (0, 1).
    seed : int, SeedSequence or Generator
        Seed of the split.

    Returns
    -------
    (train_ids, heldout_ids) : lists of str
        Held-out ids are ground-motion records only (at least two).
    """
    tf = check_train_fraction(train_fraction)
    gm = [r.id for r in campaign.ground_motion]
    if len(gm) < 4:
        raise ValueError(
            f"campaign {campaign.name!r} has {len(gm)} ground-motion record(s); the diagnosis needs at least 4 "
            "(some to fit on, at least two to judge on)"
        )
    rng = np.random.default_rng(seed)
    order = rng.permutation(len(gm))
    n_train = min(max(int(round(tf * len(gm))), 1), len(gm) - 2)
    train = [r.id for r in campaign.free_vibration] + [gm[i] for i in sorted(order[:n_train])]
    held = [gm[i] for i in sorted(order[n_train:])]
    return train, held


class Scorer:
    """Per-record time-history errors of a list of effects on a fixed set of records.

    Parameters
    ----------
    campaign : Campaign
    ids : sequence of str
        The records to score on.
    engine_settings : dict, optional
        Settings of the analytic engine (``r``, ``substeps``).

    Attributes
    ----------
    records : list of MeasuredRecord
        The records, each cut :data:`_WINDOW_SLACK` s after its error window.
    ends : list of int
        The error window of each record [samples].
    release_angle : bool
        Whether a free vibration's release angle is fitted as a nuisance parameter (one more run of each).
    """

    def __init__(self, campaign: Campaign, ids: Sequence[str], engine_settings: dict | None = None):
        self.campaign = campaign
        alpha = campaign.specimen.alpha
        recs = [campaign.record(i) for i in ids]
        self.ends = [error_window(r, alpha) for r in recs]
        # Only the window counts, so the model is run to its end (plus the largest time lag the
        # library allows, 0.1 s, and a margin): the rest of a record would cost time and change nothing.
        self.records: list[MeasuredRecord] = [_truncated(r, end) for r, end in zip(recs, self.ends, strict=True)]
        self.engine_settings = dict(engine_settings or {})
        self.n_evaluations = 0
        self._fv = np.array([r.kind == "free_vibration" for r in self.records])
        # the release angle of a free vibration as a nuisance parameter costs one more run of each
        # (history_error.release_error); the basin-finding grids of the mechanics effects do without it
        self.release_angle = True

    def subset(self, ids: Sequence[str]) -> Scorer:
        """The same scorer on the records of ``ids`` only (its evaluation count restarts)."""
        out = Scorer.__new__(Scorer)
        keep = [i for i, r in enumerate(self.records) if r.id in set(ids)]
        out.campaign = self.campaign
        out.records = [self.records[i] for i in keep]
        out.ends = [self.ends[i] for i in keep]
        out.engine_settings = self.engine_settings
        out.n_evaluations = 0
        out._fv = self._fv[keep]
        out.release_angle = self.release_angle
        return out

    def loss(self, effects: Sequence[Any]) -> float:
        """The fitting objective [alpha]: the mean error of the free vibrations and the mean error of
        the ground motions, averaged with equal weights (one group alone: its mean).

        A free vibration is not chaotic: a correct model scores its noise to within ~2 %, so a few of
        them pin p, r and the contact law (seed section 3.2), while a ground motion's error scatters by
        tens of per cent with the chaos. A plain mean over ~60 records would let that scatter outvote
        the three free vibrations, and fits (the fold refits above all) would wander off what they pin.
        """
        return self.weigh(self.errors(effects))

    def noise_loss(self) -> float:
        """:meth:`loss` of a model that left nothing but the sensor noise [alpha]: each record's noise
        sigma / alpha in place of its error, the least a model can score without fitting noise."""
        alpha = self.campaign.specimen.alpha
        return self.weigh(np.array([r.noise / alpha for r in self.records]))

    def weigh(self, e: np.ndarray) -> float:
        """:meth:`loss` of per-record errors ``e`` (in the order of :attr:`records`) [alpha]."""
        fv = self._fv
        if fv.all() or not fv.any():
            return float(e.mean())
        return 0.5 * float(e[fv].mean()) + 0.5 * float(e[~fv].mean())

    def errors(self, effects: Sequence[Any]) -> np.ndarray:
        """Error per record [alpha]; a record the model fails on scores the clip value (1).

        Raises
        ------
        NonFiniteHistory
            The model's theta history is not finite on a record (the first is named): no score is
            made of it (a clipped error would pass for a poor fit, and one per record for a floor).
        NonFiniteScore
            An error came out non-finite all the same.
        """
        self.n_evaluations += 1
        key = _model_key(effects)
        memo = self.__dict__.setdefault("_memo", {})
        if key is not None and key in memo:
            return memo[key].copy()
        out = self._errors_of(range(len(self.records)), effects)
        if key is not None:
            if len(memo) >= _MEMO_SIZE:
                memo.pop(next(iter(memo)))
            memo[key] = out.copy()
        return out

    def loss_below(self, effects: Sequence[Any], bound: float) -> float:
        """:meth:`loss`, or, once the records scored first put it above ``bound``, a lower bound of it.

        The records are scored in stages (:meth:`stages`: the free vibrations, then the ground motions
        from the shortest error window to the longest); an error is never negative, so the weighted
        sum of the errors scored so far is a lower bound of the loss, and when it exceeds ``bound``
        the rest are not simulated. Any value returned that is at most ``bound`` is :meth:`loss`
        exactly (the same errors, the same sum); a value above it is the loss or less. A grid search
        passes its best value so far: a point abandoned cannot be the best (no statistic changes).
        """
        stages = self.stages()
        key = _model_key(effects)
        memo = self.__dict__.get("_memo", {})
        if len(stages) < 2 or not math.isfinite(bound) or (key is not None and key in memo):
            return self.loss(effects)
        w = self._weights()
        out = np.empty(len(self.records))
        part = 0.0
        for j, idx in enumerate(stages):
            try:
                e = self._errors_of(idx, effects)
            except NonFiniteScore:
                return self.loss(effects)  # raised as the whole evaluation raises it (its first record named)
            out[idx] = e
            part += float(np.dot(w[idx], e))
            if part > bound * (1.0 + 1e-12) and j < len(stages) - 1:
                self.n_evaluations += 1
                return part
        return self._remember(key, out)

    def _remember(self, key, out: np.ndarray) -> float:
        """:meth:`loss` of the errors ``out`` of every record, kept as :meth:`errors` keeps them."""
        self.n_evaluations += 1
        if key is not None:
            memo = self.__dict__.setdefault("_memo", {})
            if len(memo) >= _MEMO_SIZE:
                memo.pop(next(iter(memo)))
            memo[key] = out.copy()
        return self.weigh(out)

    def _weights(self) -> np.ndarray:
        """Each record's weight in :meth:`weigh` [-] (the loss is their dot product with the errors)."""
        fv = self._fv
        n_fv, n_gm = int(fv.sum()), int((~fv).sum())
        if n_fv == 0 or n_gm == 0:
            return np.full(fv.size, 1.0 / fv.size)
        return np.where(fv, 0.5 / max(n_fv, 1), 0.5 / max(n_gm, 1))

    def stages(self) -> list[np.ndarray]:
        """The records in the order :meth:`loss_below` scores them (indices into :attr:`records`).

        The free vibrations first (half the loss, a few records), then the ground motions by the
        length of their error window, shortest first, in :data:`_STAGES` groups: the short windows
        are cheap, and a model that is off shows first where the block rocks.
        """
        if "_stages" not in self.__dict__:
            fv = np.flatnonzero(self._fv)
            gm = np.flatnonzero(~self._fv)
            gm = gm[np.argsort([self.records[i].theta.size for i in gm], kind="stable")]
            groups = [g for g in np.array_split(gm, min(_STAGES, gm.size)) if g.size] if gm.size else []
            self._stages = [g for g in [fv, *groups] if g.size]
        return self._stages

    def _errors_of(self, idx, effects: Sequence[Any]) -> np.ndarray:
        """The errors of the records ``idx`` (indices into :attr:`records`) [alpha] (:meth:`errors`)."""
        idx = list(idx)
        records = [self.records[i] for i in idx]
        ends = [self.ends[i] for i in idx]
        alpha = self.campaign.specimen.alpha
        spec = self.campaign.specimen
        res = simulate_records(spec, records, "housner", effects, self.engine_settings)
        for rec, r in zip(records, res, strict=True):
            if non_finite(r):
                names = [getattr(e, "name", str(e)) for e in effects]
                raise NonFiniteHistory(
                    f"{model_text(effects)} gives a non-finite theta history on record {rec.id!r}: "
                    "it is refused before any score",
                    names,
                    rec.id,
                )
        sens = (
            release_sensitivities(spec, records, res, "housner", effects, self.engine_settings)
            if self.release_angle
            else [None] * len(res)
        )
        out = np.empty(len(records))
        for k, (rec, r, end) in enumerate(zip(records, res, ends, strict=True)):
            out[k] = ERROR_CLIP if isinstance(r, str) else scored_error(r.theta, rec, end, alpha, sens[k])
        check_finite(f"the time-history error of {model_text(effects)}", out, [r.id for r in records])
        return out


#: Models whose errors a scorer keeps (the last ones scored) [-]: a fit's best point is scored again
#: by the checks that follow it.
_MEMO_SIZE = 64
#: Groups of ground motions :meth:`Scorer.loss_below` scores one after the other [-].
_STAGES = 4


def _model_key(effects: Sequence[Any]):
    """A key of a model (its effects, which are frozen dataclasses) for the scorer's memo; None if unhashable."""
    key = tuple((type(e), e) for e in effects)
    try:
        hash(key)
    except TypeError:
        return None
    return key


def non_finite(result: Any) -> bool:
    """Whether one result of :func:`simulate_records` (a response, a theta history [rad] or a failure's
    message) is a non-finite history."""
    if isinstance(result, str):
        return any(m in result for m in _NON_FINITE_MARKS)
    theta = result if isinstance(result, np.ndarray) else getattr(result, "theta", None)
    return theta is not None and not bool(np.all(np.isfinite(np.asarray(theta, dtype=float))))


#: Samples simulated beyond the end of the error window [s] (the library's largest time lag is 0.1 s).
_WINDOW_SLACK = 0.25


def _truncated(rec: MeasuredRecord, end: int) -> MeasuredRecord:
    """``rec`` cut :data:`_WINDOW_SLACK` after sample ``end`` (itself when it ends before)."""
    n = min(rec.theta.size, end + int(math.ceil(_WINDOW_SLACK / rec.dt)))
    if n >= rec.theta.size:
        return rec
    return replace(
        rec,
        motion=rec.motion.sliced(0, n),
        t=rec.t[:n],
        theta=rec.theta[:n],
        valid=None if rec.valid is None else rec.valid[:n],
    )


def decimation_factor(campaign: Campaign, rate: float = SEARCH_RATE) -> int:
    """The factor q >= 1 by which :func:`decimated` thins every record of ``campaign`` (1: not at all).

    The largest whole q that keeps every record at ``rate`` [Hz] or above (and at
    :data:`_MIN_DECIMATED` samples or more).
    """
    if not campaign.records:
        return 1
    q = min(int(math.floor(1.0 / (r.dt * rate) + 1e-9)) for r in campaign.records)
    while q >= 2 and min(r.theta.size for r in campaign.records) // q < _MIN_DECIMATED:
        q -= 1
    return max(q, 1)


def decimated(campaign: Campaign, q: int | None = None) -> tuple[Campaign, int]:
    """``campaign`` on every q-th sample (q = :func:`decimation_factor` by default), and q.

    theta is taken as sampled (no filter): its noise stays white of the same sigma, so each
    record's time-history error is the same mean square over every q-th sample, the same
    statistic on fewer samples. The table acceleration (and every extra channel) is the model's
    input: it is low-passed below the new Nyquist frequency first (a zero-phase polyphase FIR,
    :func:`scipy.signal.resample_poly`), so that what the table did above it does not fold back.
    The noise sigma, the release angle, the sensor's range and its mask of faulty samples (thinned
    alike) are kept. Returns ``campaign`` itself when q is 1.
    """
    q = decimation_factor(campaign) if q is None else int(q)
    if q < 2:
        return campaign, 1
    recs = [_decimated_record(r, q) for r in campaign.records]
    return replace(campaign, records=recs), q


def _decimated_record(rec: MeasuredRecord, q: int) -> MeasuredRecord:
    """``rec`` on its samples 0, q, 2q, ... (module docstring)."""

    def low(x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        return signal.resample_poly(x, 1, q, padtype="line")[: (x.size + q - 1) // q]

    m = rec.motion
    motion = replace(m, acc=low(m.acc), dt=m.dt * q, channels={k: low(c) for k, c in m.channels.items()})
    return replace(
        rec, motion=motion, t=rec.t[::q], theta=rec.theta[::q], valid=None if rec.valid is None else rec.valid[::q]
    )


def cv_folds(campaign: Campaign, folds: int = DEFAULT_FOLDS, seed=0) -> list[list[str]]:
    """Every record in one of ``folds`` folds: free vibrations dealt first, then ground motions, each shuffled.

    Dealing the free vibrations first spreads them over different folds, so each is held out once
    and the others train (they pin p and r, seed section 3.2).

    Parameters
    ----------
    campaign : Campaign
    folds : int
        Number of folds K [-], at least 2.
    seed : int, SeedSequence or Generator
        Seed of the assignment.

    Returns
    -------
    list of K lists of record ids, each in campaign order.
    """
    k = int(folds)
    if k < 2:
        raise ValueError(f"`folds` must be at least 2, got {folds!r}")
    rng = np.random.default_rng(seed)
    out: list[list[str]] = [[] for _ in range(k)]
    j = 0
    for group in ([r.id for r in campaign.free_vibration], [r.id for r in campaign.ground_motion]):
        for i in rng.permutation(len(group)):
            out[j % k].append(group[int(i)])
            j += 1
    order = {r.id: i for i, r in enumerate(campaign.records)}
    return [sorted(f, key=order.__getitem__) for f in out]
