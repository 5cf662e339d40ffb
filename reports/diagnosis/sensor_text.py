"""The theta sensor's assessment in words: its noise, each fault and what was done, the notes, and what the
verdict adds about them, all read from the values of :mod:`housner.scenarios.diagnosis.sensor_assessment`."""

from __future__ import annotations

import math

from housner.scenarios.campaigns.sensor_noise import SensorNoise
from housner.scenarios.diagnosis.sensor_assessment import SensorFault, SensorReport

__all__ = [
    "fault_text",
    "noise_text",
    "sensor_document",
    "sensor_notes",
    "sensor_text",
    "sensor_verdict_sentence",
]


def noise_text(noise: SensorNoise) -> str:
    """One line: what the noise is."""
    if noise.n_samples == 0:
        return "not measured (no quiet part of the records): white noise of the difference-based sigma assumed"
    if noise.white:
        return (
            f"white (Ljung-Box p = {noise.pvalue:.2g} on {noise.n_samples} quiet samples), sigma "
            f"{noise.sigma * 1e3:.3g} mrad"
        )
    return (
        f"correlated in time: sigma {noise.sigma * 1e3:.3g} mrad, {noise.diff_ratio:.2f}x the estimate from "
        f"differences, correlation time {noise.correlation_time * 1e3:.3g} ms (measured on "
        f"{noise.n_samples} quiet samples; Ljung-Box p = {noise.pvalue:.2g})"
    )


def _saturation(f: SensorFault) -> str:
    alpha = f.figures["alpha"]
    limits = [v for v in (f.figures["low"], f.figures["high"]) if math.isfinite(v)]
    rng = " and ".join(f"{v:+.4g} rad ({v / alpha:+.2f} alpha)" for v in limits)
    return (
        f"saturation: {len(f.records)} record(s) flat-topped at {rng}, the sensor's range; their {f.samples} "
        "samples at it are left out of every error, and models are read through the same range."
    )


def _spikes(f: SensorFault) -> str:
    return (
        f"spikes: {f.samples} single samples in {len(f.records)} record(s) lie more than {f.figures['sigmas']:g} "
        "robust sigmas off both neighbours; they are left out of the errors and bridged for the impact and peak "
        "detections."
    )


def _dropouts(f: SensorFault) -> str:
    return (
        f"dropouts: {f.samples} samples in {len(f.records)} record(s) repeat the value before them "
        f"{f.figures['run']} or more times in a row, which noise cannot do; they are left out of the errors and "
        "bridged."
    )


def _offset_drift(f: SensorFault) -> str:
    g = f.figures
    return (
        f"offset drift: the rest level after each record's motion moves by {g['change'] * 1e3:+.3g} mrad from the "
        f"first record to the last (t = {g['t']:+.1f} over {g['n']} records); theta is corrected to the first "
        "record's offset."
    )


def _gain_drift(f: SensorFault) -> str:
    g = f.figures
    return (
        "gain drift: the first large excursion of each ground motion against the plain model's reads "
        f"{g['relative_change'] * 100:+.1f} % more from the first record to the last (t = {g['t']:+.1f} over "
        f"{g['n']} ground motions, each before any impact large enough for an impact law to matter); theta is "
        "corrected to the first record's gain."
    )


_FAULTS = {
    "saturation": _saturation,
    "spikes": _spikes,
    "dropouts": _dropouts,
    "offset_drift": _offset_drift,
    "gain_drift": _gain_drift,
}


def fault_text(fault: SensorFault) -> str:
    """One sentence: the fault, the figures that named it and what was done about it."""
    return _FAULTS[fault.kind](fault)


def sensor_notes(report: SensorReport) -> list[str]:
    """What else the assessment did, one sentence each: free vibrations left out, several sample rates."""
    out = []
    if report.unseen_releases:
        out.append(
            f"{len(report.unseen_releases)} free vibration(s) ({', '.join(report.unseen_releases)}) start beyond "
            "the sensor's range, so their release angle was not measured: left out."
        )
    if report.mixed_rates:
        out.append("The records have different sample rates: the noise is treated as white.")
    return out


def sensor_text(report: SensorReport) -> str:
    """One paragraph: the noise, then each fault and what was done."""
    out = f"Sensor noise: {noise_text(report.noise)}."
    if not report.noise.white and math.isfinite(report.sigma_before):
        out += (
            f" Each record's sigma is the difference-based estimate times {report.noise.diff_ratio:.2f} "
            f"(mean {report.sigma_before * 1e3:.3g} -> {report.sigma_after * 1e3:.3g} mrad), and the floor's "
            "replicas draw noise of this correlation."
        )
    for f in report.faults:
        out += " Sensor fault: " + fault_text(f)
    for n in sensor_notes(report):
        out += " " + n
    return out


def sensor_verdict_sentence(report: SensorReport) -> str:
    """What the verdict adds about the sensor: its faults and what was done, and a noise that is not white
    ('' when the sensor is white and faultless)."""
    bits = [fault_text(f) for f in report.faults]
    if not report.noise.white:
        bits.append(
            f"the sensor's noise is correlated in time ({noise_text(report.noise)}); the floor was measured "
            "with noise of that correlation"
        )
    bits += sensor_notes(report)
    if not bits:
        return ""
    names = ", ".join(f.kind.replace("_", " ") for f in report.faults)
    head = f" The sensor, not the physics: {names}." if report.faults else ""
    return head + " " + " ".join(b[0].upper() + b[1:] + ("" if b.endswith(".") else ".") for b in bits)


def sensor_document(report: SensorReport) -> dict:
    """The sensor's entry of the diagnosis JSON: its data (:meth:`SensorReport.to_dict`) with the words beside
    them (the noise's, each fault's, the notes and the paragraph)."""
    data = report.to_dict()
    data["noise"] = {**data["noise"], "text": noise_text(report.noise)}
    data["faults"] = [{**d, "text": fault_text(f)} for d, f in zip(data["faults"], report.faults, strict=True)]
    return {**data, "notes": sensor_notes(report), "text": sensor_text(report)}
