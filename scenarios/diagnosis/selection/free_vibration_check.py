"""The diagnosis' free-vibration check: a candidate model must not contradict what the free vibrations pin.

The free vibrations pin p and r (seed section 3.2). A candidate whose free-vibration localisation
(:data:`FV_CHECK`, observed through the campaign's sensor as in
:func:`housner.scenarios.diagnosis.comparison.record_comparison.compare`) lies more than :data:`FV_Z` standard errors
from
the measured one, and further than the plain model's, is not held out
(:meth:`FreeVibrationCheck.reason`).
"""

from __future__ import annotations

import math

from housner.scenarios.campaigns.campaign import Campaign
from housner.scenarios.diagnosis.comparison.localise import features
from housner.scenarios.diagnosis.comparison.record_comparison import observe, on_grid, simulate_records
from housner.scenarios.diagnosis.selection.reasons import Reason

__all__ = ["FV_CHECK", "FV_Z", "FreeVibrationCheck", "fv_metrics"]

#: Free-vibration localisation quantities a candidate must not contradict (seed section 3.2: they
#: pin p and r), and the |z| beyond which it does (when it is also worse than the current model's).
FV_CHECK = ("p", "energy_ratio")
FV_Z = 3.0


def fv_metrics(campaign: Campaign, effects: list, engine_settings) -> dict:
    """Free-vibration localisation (p, energy ratio) of a model, observed through the campaign's sensor."""
    fv = campaign.free_vibration
    if not fv:
        return {}
    res = simulate_records(campaign.specimen, fv, "housner", effects, engine_settings)
    index = {r.id: i for i, r in enumerate(campaign.records)}
    hist, over = {}, {}
    for rec, r in zip(fv, res, strict=True):
        if isinstance(r, str):
            continue
        hist[rec.id] = observe(on_grid(r, rec), rec, index[rec.id])
        over[rec.id] = bool(r.overturned)
    if not hist:
        return {}
    m = features(campaign, hist, over).metrics()
    return {k: m[k] for k in FV_CHECK}


def _fv_z(model: dict, measured: dict) -> dict[str, float]:
    out = {}
    for k in FV_CHECK:
        a, b = measured.get(k), model.get(k)
        if a is None or b is None or not (math.isfinite(a.value) and math.isfinite(b.value)):
            continue
        se = math.hypot(a.se if math.isfinite(a.se) else 0.0, b.se if math.isfinite(b.se) else 0.0)
        if se > 0:
            out[k] = (b.value - a.value) / se
    return out


class FreeVibrationCheck:
    """Models against the measured free-vibration localisation of a campaign.

    Parameters
    ----------
    campaign : Campaign
    engine_settings : dict or None
        Settings of the analytic engine.
    measured : dict
        The measured localisation quantities (``Features.metrics()``).
    """

    def __init__(self, campaign: Campaign, engine_settings, measured: dict):
        self.campaign, self.engine_settings = campaign, engine_settings
        self.measured = {k: v for k, v in measured.items() if k in FV_CHECK}
        #: the plain model's z of each quantity: a candidate is only blamed for going further
        self.plain_z = self.z([])

    def z(self, model_effects: list) -> dict[str, float]:
        """Each quantity of :data:`FV_CHECK`: the model's distance from the measured value [standard errors]."""
        return _fv_z(fv_metrics(self.campaign, model_effects, self.engine_settings), self.measured)

    def reason(self, model_effects: list) -> Reason | None:
        """Why a model contradicts the free vibrations (:data:`FV_CHECK` beyond :data:`FV_Z`), None if it does not."""
        for k, v in self.z(model_effects).items():
            if abs(v) > FV_Z and abs(v) > abs(self.plain_z.get(k, 0.0)):
                m = self.measured[k]
                return Reason("free_vibrations", {"quantity": k, "z": v, "measured": m.value, "se": m.se})
        return None
