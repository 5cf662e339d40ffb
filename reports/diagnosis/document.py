"""The diagnosis JSON as the command line writes it: the result's data
(:meth:`housner.scenarios.diagnosis.results.DiagnosisResult.to_json`) with its words, the verdict's paragraph, where
the model still differs and the one-paragraph summary (:mod:`housner.reports.diagnosis.verdict_text`)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

from housner._values import to_data
from housner.reports.diagnosis.reason_text import reason_text
from housner.reports.diagnosis.sensor_text import sensor_document
from housner.reports.diagnosis.verdict_text import (
    diagnosis_summary,
    distribution_text,
    economy_text,
    verdict_paragraph,
    where_texts,
)

if TYPE_CHECKING:
    from housner.scenarios.diagnosis.results import Candidate, Diagnosis

__all__ = ["diagnosis_document", "write_diagnosis_json"]


def diagnosis_document(diag: Diagnosis) -> dict:
    """The diagnosis JSON's content: the data of :meth:`Diagnosis.result`, the verdict's ``text``, ``where`` and
    ``distribution`` in words, the settings' ``economies`` in words (beside their ``economy_facts``), and the
    ``summary`` (before ``elapsed_s``)."""
    data = diag.result().to_json()
    sensor = getattr(diag.campaign, "sensor", None)
    if sensor is not None:
        data["sensor"] = to_data(sensor_document(sensor))
    v = diag.verdict
    if v is not None:
        words = {
            "text": verdict_paragraph(diag),
            "where": where_texts(v),
            "distribution": [distribution_text(d) for d in v.distribution],
        }
        data["verdict"] = {**data["verdict"], **words}
    settings = data["settings"]
    facts = settings.pop("economy_facts")
    data["settings"] = {
        **settings,
        "economies": [economy_text(e) for e in diag.settings.economies],
        "economy_facts": facts,
    }
    data["candidates"] = [_with_reason(c, d) for c, d in zip(diag.candidates, data["candidates"], strict=True)]
    data["rounds"] = [
        [_with_reason(c, d) for c, d in zip(r, rd, strict=True)]
        for r, rd in zip(diag.rounds, data["rounds"], strict=True)
    ]
    elapsed = data.pop("elapsed_s")
    return {**data, "summary": diagnosis_summary(diag), "elapsed_s": elapsed}


def _with_reason(c: Candidate, data: dict) -> dict:
    """A candidate's data with its reason in words (``reason``) before its figures (``reason_facts``)."""
    out = {}
    for k, v in data.items():
        if k == "reason_facts":
            out["reason"] = reason_text(c.reason)
        out[k] = v
    return out


def write_diagnosis_json(diag: Diagnosis, path: str | Path, extra: dict | None = None) -> None:
    """Write :func:`diagnosis_document` (with ``extra``'s keys added: a campaign of both kinds adds its outcome
    diagnosis) to ``path``, strict JSON (no NaN: :meth:`DiagnosisResult.to_json` wrote null there)."""
    text = json.dumps({**diagnosis_document(diag), **(extra or {})}, indent=2, allow_nan=False)
    Path(path).write_text(text + "\n")
