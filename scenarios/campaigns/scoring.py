"""The records a diagnosis fits and judges on: the split into folds, and a model's errors on a set of records.

:func:`cv_folds` deals every record into one of K folds (the diagnosis'
cross-validation), :func:`split_records` makes the older single split, and
:class:`Scorer` runs the analytic engine on a fixed set of records (each cut
to its error window) and scores a list of effects by the time-history error
of :mod:`housner.scenarios.campaigns.history_error` [alpha].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from housner.scenarios.campaigns.campaign import Campaign, MeasuredRecord
from housner.scenarios.campaigns.compare import release_sensitivities, simulate_records
from housner.scenarios.campaigns.history_error import ERROR_CLIP, error_window, scored_error

__all__ = ["DEFAULT_FOLDS", "Scorer", "check_train_fraction", "cv_folds", "split_records"]

#: Cross-validation folds [-]: every record is held out once, so the answer rests on all of them
#: and depends far less on the assignment than one random split does.
DEFAULT_FOLDS = 5


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
        """Error per record [alpha]; a record the model fails on scores the clip value (1)."""
        self.n_evaluations += 1
        alpha = self.campaign.specimen.alpha
        spec = self.campaign.specimen
        res = simulate_records(spec, self.records, "housner", effects, self.engine_settings)
        sens = (release_sensitivities(spec, self.records, res, "housner", effects, self.engine_settings)
                if self.release_angle else [None] * len(res))  # fmt: skip
        out = np.empty(len(self.records))
        for k, (rec, r, end) in enumerate(zip(self.records, res, self.ends, strict=True)):
            out[k] = ERROR_CLIP if isinstance(r, str) else scored_error(r.theta, rec, end, alpha, sens[k])
        return out


#: Samples simulated beyond the end of the error window [s] (the library's largest time lag is 0.1 s).
_WINDOW_SLACK = 0.25


def _truncated(rec: MeasuredRecord, end: int) -> MeasuredRecord:
    """``rec`` cut :data:`_WINDOW_SLACK` after sample ``end`` (itself when it ends before)."""
    n = min(rec.theta.size, end + int(math.ceil(_WINDOW_SLACK / rec.dt)))
    if n >= rec.theta.size:
        return rec
    return replace(rec, motion=rec.motion.sliced(0, n), t=rec.t[:n], theta=rec.theta[:n])


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
