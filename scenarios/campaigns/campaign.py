"""Measurement campaigns: a specimen and its measured records, read from a campaign directory.

A campaign is a directory with ``campaign.toml`` (name, ``[specimen]``, one ``[[record]]`` per test; read
and checked by :mod:`housner.scenarios.campaigns.campaign_toml`) and one CSV per record
(:mod:`housner.scenarios.campaigns.campaign_records`: ``time`` [s], ``ground_acc`` [m/s^2], ``theta`` [rad]
and optional channels, units in the header converted once to SI). :func:`load_campaign` reads it into a
:class:`Campaign` whose records carry the measured rotation and the ground motion that drives a model of the
same test (:class:`housner.GroundMotion`, with the initial angle of a free-vibration release). Paths must
resolve inside the campaign folder unless ``allow_outside=True``; a malformed ``campaign.toml`` raises
:class:`housner.errors.DataFileError` naming the key, a malformed record is left out and listed in
:attr:`Campaign.skipped`, and the campaign is refused when more than half of its records cannot be read. The
format, its paths and its errors are in ``docs/reference/campaign-format.md``.
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass, field, replace
from pathlib import Path

from housner.errors import DataFileError, unknown_choice
from housner.scenarios.campaigns.campaign_records import MeasuredRecord, OutcomeRecord, read_record
from housner.scenarios.campaigns.campaign_toml import key_line, path_outside, read_campaign_toml
from housner.specimen import Specimen
from housner.units import G

__all__ = ["Campaign", "load_campaign"]


@dataclass(eq=False)
class Campaign:
    """A measurement campaign: the specimen and its records.

    Attributes
    ----------
    name : str
    specimen : Specimen
        From ``[specimen]`` (2H, 2B, depth, mass, optional p).
    records : list of MeasuredRecord
        The records that were read, in the order of campaign.toml.
    skipped : list of (str, str, str)
        (record id, file, error message) of each record left out.
    path : pathlib.Path
        The campaign directory.
    outcomes : list of OutcomeRecord
        The records with only an observed outcome (no theta channel), in the order of campaign.toml.
    scan : housner.scan.ScanSpecimen or None
        The specimen's scan-mesh derivation (per-side alpha, p, its alpha bracket) when ``[specimen]`` names a
        ``mesh``; ``specimen`` is then its equivalent block.
    sensor : housner.scenarios.diagnosis.sensor_assessment.SensorReport or None
        What the assessment of the theta sensor found (its noise, its faults and what was done about them);
        None until :func:`housner.scenarios.diagnosis.sensor_assessment.assess_sensor` ran.
    g : float
        The local gravity where it was measured [m/s^2] (campaign.toml's ``g``; standard gravity by default). The
        records' table accelerations are kept as the model reads them (:func:`at_standard_gravity`).
    """

    name: str
    specimen: Specimen
    records: list[MeasuredRecord]
    skipped: list[tuple[str, str, str]] = field(default_factory=list)
    path: Path = Path(".")
    outcomes: list[OutcomeRecord] = field(default_factory=list)
    scan: object = None
    sensor: object = None
    g: float = G
    _cache: dict = field(default_factory=dict, init=False, repr=False)

    @property
    def free_vibration(self) -> list[MeasuredRecord]:
        """The free-vibration records."""
        return [r for r in self.records if r.kind == "free_vibration"]

    @property
    def ground_motion(self) -> list[MeasuredRecord]:
        """The ground-motion (shake-table) records."""
        return [r for r in self.records if r.kind == "ground_motion"]

    @property
    def outcome_groups(self) -> list[str]:
        """The group of each outcome record, in the order of :attr:`outcomes`: its ``group`` (the ground motion
        it played), or its id where it has none (a group of its own). Records of one group were shaken by the
        same motion, so a held-out fold keeps them together."""
        return _groups(self.outcomes)

    @property
    def record_groups(self) -> list[str]:
        """The group of each theta record, in the order of :attr:`records`, as :attr:`outcome_groups`."""
        return _groups(self.records)

    def record(self, rid: str) -> MeasuredRecord:
        """The record with id ``rid`` (ValueError listing the ids when unknown)."""
        for r in self.records:
            if r.id == rid:
                return r
        raise unknown_choice("record", rid, [r.id for r in self.records])

    def __len__(self) -> int:
        return len(self.records)

    def __repr__(self) -> str:
        outcomes = f" + {len(self.outcomes)} outcome records" if self.outcomes else ""
        return (
            f"Campaign({self.name!r}, {len(self.free_vibration)} free-vibration + {len(self.ground_motion)} "
            f"ground-motion records{outcomes}, {len(self.skipped)} skipped)"
        )


def load_campaign(path: str | Path, allow_outside: bool = False) -> Campaign:
    """Read a measurement campaign.

    Parameters
    ----------
    path : path
        The campaign directory (or its ``campaign.toml``).
    allow_outside : bool
        Read record files and a mesh that resolve outside the campaign folder (default False: such a
        record is left out and listed in ``skipped``, such a mesh refuses the campaign, each with one
        line naming the key, the path and the folder).

    Returns
    -------
    Campaign
        Records that could not be read are listed in ``skipped`` with the
        error (file, line and column), the others kept.

    Raises
    ------
    housner.errors.DataFileError
        (a ValueError) ``campaign.toml`` is missing or malformed (the message
        names the key and, where known, the line), or more than half of the
        records could not be read: then one line names the campaign, the
        count ("87 of 103 records could not be read") and the most common
        cause with one example file. A minority of unreadable records is
        left out and listed in ``skipped``.

    Notes
    -----
    A free-vibration record starts at the release: its initial angle is
    fitted to the first samples
    (:func:`housner.scenarios.campaigns.campaign_records.estimate_release`) and becomes the
    motion's ``theta0`` (with ``theta_dot0`` = 0); samples of a hold before
    the release are dropped. A record file whose time column does not start
    at 0 is taken as starting at its first sample.
    """
    p = Path(path)
    toml = p if p.suffix == ".toml" else p / "campaign.toml"
    root = toml.parent
    checked = read_campaign_toml(toml, allow_outside)
    name, specimen, scan, text, entries = checked.name, checked.specimen, checked.scan, checked.text, checked.records
    records, outcomes, skipped, errors = [], [], [], []
    for i, rec in enumerate(entries):
        try:
            outside = None if allow_outside else path_outside(root / rec["file"], root)
            if outside is not None:
                raise DataFileError(
                    toml,
                    f"record {rec['id']!r}: file {rec['file']!r} {outside}",
                    line=key_line(text, "file", "record", i),
                )
            r = at_standard_gravity(read_record(root, rec, specimen), checked.g)
            if isinstance(r, MeasuredRecord):
                r = replace(r, position=i)
        except DataFileError as e:
            skipped.append((rec["id"], rec["file"], str(e)))
            errors.append(e)
            continue
        (outcomes if isinstance(r, OutcomeRecord) else records).append(r)
    if 2 * len(skipped) > len(entries):
        raise DataFileError(toml, _unreadable_message(name, len(entries), skipped, errors))
    return Campaign(
        name=name,
        specimen=specimen,
        records=records,
        skipped=skipped,
        path=root,
        outcomes=outcomes,
        scan=scan,
        g=checked.g,
    )


def at_standard_gravity(record, g: float):
    """``record`` with its table accelerations as the model reads them: x G / g, so that a_g / G, the ratio the
    model's equation of motion feels (with p stated), is the measured a_g / g of the campaign's local ``g``
    [m/s^2]. The block's rocking under a table motion depends on g only through that ratio and through p
    (``docs/reference/campaign-format.md``, "Local gravity")."""
    if g == G:
        return record
    k = G / g
    mo = record.motion
    return replace(
        record,
        motion=replace(mo, acc=mo.acc * k, channels={c: a * k for c, a in mo.channels.items()}),
    )


def _groups(records: list) -> list[str]:
    """Each record's ``group``, or its id where it has none."""
    return [r.id if r.group is None else r.group for r in records]


def _cause(e: DataFileError) -> tuple[str, str]:
    """The message of a record's error without its file and line, and that message with its numbers blanked
    (errors of the same cause share the latter)."""
    text = " ".join(str(e).split())  # one line
    where = (
        str(e.path)
        + (f" line {e.line}" if e.line is not None else "")
        + (f", column `{e.column}`" if e.column is not None else "")
    )
    msg = text[len(where) + 2 :] if text.startswith(where + ": ") else text
    return msg, re.sub(r"[-+]?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?", "#", msg)


def _unreadable_message(name: str, n: int, skipped: list, errors: list[DataFileError]) -> str:
    """One line: the campaign, how many of its ``n`` records could not be read, the most common cause, an example."""
    causes = [_cause(e) for e in errors]
    key, k = Counter(c[1] for c in causes).most_common(1)[0]
    first = next(i for i, c in enumerate(causes) if c[1] == key)
    ex = errors[first]
    where = f"record {skipped[first][0]!r}, {skipped[first][1]}"
    where += (f" line {ex.line}" if ex.line is not None else "") + (
        f", column `{ex.column}`" if ex.column is not None else ""
    )
    none = "no record could be read: " if len(errors) == n else ""
    return (
        f"campaign {name!r}: {none}{len(errors)} of {n} records could not be read, more than half, so the campaign "
        f"is not diagnosed; most common cause ({k} of them): {causes[first][0]} (e.g. {where})"
    )
