"""Hostile and careless files: paths that leave their folder, files that are not records, one input rule for
every reader, bad plugins, a user's own files in ``--out`` (issue 41, parts 2 and 6).

Each case builds its files under ``tmp_path`` and fails before any simulation.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from housner.cli import main
from housner.cli.app import build_parser
from housner.errors import DataFileError
from housner.motion import GroundMotion
from housner.readers.measured_data import DECLARED_ACC_CEILING, MIN_RECORD_SAMPLES, PLAUSIBLE_ACC, read_csv_si
from housner.scenarios.campaigns import campaign as campaign_module
from housner.scenarios.campaigns.campaign import load_campaign
from housner.scenarios.catalogue import ScenarioError
from housner.scenarios.catalogue.scenario import load_scenario
from housner.scenarios.execution.outputs import OutputPathError, check_output_dir
from housner.scenarios.execution.rundir import RUN_FILES, provenance
from housner.units import G

#: The first line of a system's password file: it must never reach a message.
PASSWD = "root:x:0:0:root:/root:/bin/bash\ndaemon:x:1:1:daemon:/usr/sbin:/usr/sbin/nologin\n"

SPECIMEN = """[specimen]
height = 0.5
width = 0.075
depth = 0.4
mass = 3.94
p = 4.8883
"""

SCENARIO = """name = "own"
[specimen]
preset = "bachmann2017"
[motions]
source = "record"
{motions}
[engines]
names = ["housner"]
"""


def record_csv(n: int = 400, peak: float = 0.5, header: str = "time,ground_acc,theta") -> str:
    """A small ground-motion record: ``peak`` [in the header's acceleration unit], theta at rest."""
    t = np.arange(n) * 0.002
    acc = peak * np.sin(2 * np.pi * 3 * t)
    return header + "\n" + "".join(f"{a:.4f},{b:.6e},0.0\n" for a, b in zip(t, acc, strict=True))


def make_campaign(folder: Path, records: dict[str, str], files: dict[str, str] | None = None) -> Path:
    """A campaign in ``folder``: one ground-motion [[record]] per id -> file (as written), and ``files`` to write
    (relative to ``folder``) besides three good records gm01..gm03."""
    folder.mkdir(parents=True, exist_ok=True)
    good = {f"gm0{k}": f"records/gm0{k}.csv" for k in (1, 2, 3)}
    for rel in good.values():
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        (folder / rel).write_text(record_csv())
    for rel, text in (files or {}).items():
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        (folder / rel).write_text(text)
    tables = "".join(
        f'[[record]]\nid = "{rid}"\nkind = "ground_motion"\nfile = "{f}"\n' for rid, f in {**good, **records}.items()
    )
    (folder / "campaign.toml").write_text('name = "hostile"\n' + SPECIMEN + tables)
    return folder


def skipped_message(camp, rid: str) -> str:
    return next(msg for r, _f, msg in camp.skipped if r == rid)


# ---------------------------------------------------------------------------- 1. files stay in their folder
@pytest.mark.parametrize("how", ["dotdot", "absolute", "symlink"])
def test_a_campaign_record_outside_its_folder_is_skipped_by_name(tmp_path, how):
    (tmp_path / "elsewhere.csv").write_text(record_csv())
    written = {"dotdot": "../elsewhere.csv", "absolute": str(tmp_path / "elsewhere.csv"), "symlink": "link.csv"}[how]
    folder = make_campaign(tmp_path / "camp", {"x": written})
    if how == "symlink":
        os.symlink(tmp_path / "elsewhere.csv", folder / "link.csv")
    camp = load_campaign(folder)
    assert [r.id for r in camp.records] == ["gm01", "gm02", "gm03"]
    msg = skipped_message(camp, "x")
    assert "\n" not in msg
    for part in (
        "record 'x'",
        f"file {written!r}",
        f"outside the campaign folder {folder.resolve()}",
        "--allow-outside",
        "campaign.toml line 23",
    ):
        assert part in msg, (part, msg)
    # the explicit opt-out reads it
    assert "x" in [r.id for r in load_campaign(folder, allow_outside=True).records]


def test_the_password_file_is_neither_read_nor_echoed(tmp_path):
    (tmp_path / "etc").mkdir()
    (tmp_path / "etc" / "passwd").write_text(PASSWD)
    folder = make_campaign(tmp_path / "a" / "camp", {"x": "../../etc/passwd"}, {"records/passwd.csv": PASSWD})
    (folder / "campaign.toml").write_text(
        (folder / "campaign.toml").read_text() + '[[record]]\nid = "y"\nkind = "ground_motion"\n'
        'file = "records/passwd.csv"\n'
    )
    camp = load_campaign(folder)
    assert "outside the campaign folder" in skipped_message(camp, "x")
    inside = skipped_message(camp, "y")  # a file inside the folder that is not a record: read, not echoed
    assert "the first line is not a CSV header with a `time` column (31 characters" in inside
    for msg in (inside, *(m for _r, _f, m in load_campaign(folder, allow_outside=True).skipped)):
        msg = msg.replace(str(tmp_path), "")  # (the temporary folder's name may hold "root")
        assert "root" not in msg and "/bin/bash" not in msg and "x:0:0" not in msg, msg


def test_a_mesh_outside_the_campaign_folder_refuses_the_campaign(tmp_path):
    folder = tmp_path / "camp"
    make_campaign(folder, {})
    text = (folder / "campaign.toml").read_text().replace(SPECIMEN, '[specimen]\nmesh = "../../block.obj"\n')
    (folder / "campaign.toml").write_text(text)
    with pytest.raises(
        DataFileError,
        match=r"campaign\.toml line 3: \[specimen\] 'mesh' '\.\./\.\./block\.obj' "
        r"resolves outside the campaign folder .*--allow-outside",
    ):
        load_campaign(folder)
    with pytest.raises(DataFileError) as e:  # allowed: then it is read, and here it does not exist
        load_campaign(folder, allow_outside=True)
    assert "block.obj: no such file" in str(e.value) and "resolves outside" not in str(e.value)


def test_diagnose_passes_allow_outside_to_the_reader(tmp_path, monkeypatch, capsys):
    assert build_parser().parse_args(["diagnose", "c", "--allow-outside"]).allow_outside is True
    assert build_parser().parse_args(["diagnose", "c"]).allow_outside is False
    folder = make_campaign(tmp_path / "camp", {})
    seen = {}

    def fake(path, allow_outside=False):
        seen["allow_outside"] = allow_outside
        raise DataFileError(path, "stop here")

    monkeypatch.setattr(campaign_module, "load_campaign", fake)
    assert main(["diagnose", str(folder), "--allow-outside", "-q"]) == 2
    assert seen == {"allow_outside": True}
    assert "stop here" in capsys.readouterr().err


@pytest.mark.parametrize("how", ["dotdot", "absolute", "folder-link"])
def test_a_scenario_record_outside_its_folder_is_refused(tmp_path, how):
    (tmp_path / "rec.csv").write_text(record_csv(header="time,ground_acc"))
    folder = tmp_path / "scen"
    folder.mkdir()
    if how == "folder-link":
        (folder / "suite").mkdir()
        os.symlink(tmp_path / "rec.csv", folder / "suite" / "rec.csv")
        motions, key = 'records = "suite"', "records"
    else:
        written = "../rec.csv" if how == "dotdot" else str(tmp_path / "rec.csv")
        motions, key = f'record = "{written}"', "record"
    text = SCENARIO.format(motions=motions)
    if key == "records":
        text = text.replace('source = "record"', 'source = "records"')
    (folder / "s.toml").write_text(text)
    with pytest.raises(ScenarioError) as e:
        load_scenario(folder / "s.toml")
    msg = str(e.value)
    assert "\n" not in msg
    for part in (
        "s.toml line 6",
        f"[motions] {key!r}",
        f"resolves outside the scenario folder {folder.resolve()}",
        "allow_outside=True",
    ):
        assert part in msg, (part, msg)
    assert load_scenario(folder / "s.toml", allow_outside=True).n_motions == 1


def test_housner_run_refuses_an_outside_record_and_reads_it_with_allow_outside(tmp_path, capsys):
    (tmp_path / "rec.csv").write_text(record_csv(header="time,ground_acc"))
    folder = tmp_path / "scen"
    folder.mkdir()
    (folder / "s.toml").write_text(SCENARIO.format(motions='record = "../rec.csv"'))
    args = ["run", str(folder / "s.toml"), "--engines", "housner", "--no-report", "--jobs", "1"]
    assert main([*args, "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "resolves outside the scenario folder" in err and "--allow-outside" in err
    assert main([*args, "--out", str(tmp_path / "b"), "--allow-outside"]) == 0
    assert (tmp_path / "b" / "results.parquet").is_file()


def test_a_scenario_record_inside_its_folder_and_the_shipped_ones_still_load(tmp_path):
    (tmp_path / "recs").mkdir()
    (tmp_path / "recs" / "rec.csv").write_text(record_csv(header="time,ground_acc"))
    (tmp_path / "s.toml").write_text(SCENARIO.format(motions='record = "recs/../recs/rec.csv"'))
    assert load_scenario(tmp_path / "s.toml").n_motions == 1
    assert load_scenario("elcentro").source == "rdk"


# ---------------------------------------------------------------------------- 2. no echo of a file's content
def test_a_header_of_names_is_listed_cut_short(tmp_path):
    names = ["time"] + [f"c{k}_" + "x" * 60 for k in range(12)]
    path = tmp_path / "wide.csv"
    path.write_text(",".join(names) + "\n" + ",".join(["0"] * len(names)) + "\n")
    with pytest.raises(DataFileError) as e:
        read_csv_si(path, {"time": "time", "ground_acc": "acceleration"})
    msg = str(e.value)
    assert "missing column `ground_acc`" in msg and "header has: time, c0_" in msg and "(13 columns)" in msg
    assert "x" * 41 not in msg and "c9_" not in msg  # each name cut to 40 characters, the list to 10 names


@pytest.mark.parametrize(
    "first",
    [
        "root:x:0:0:root:/root:/bin/bash",
        "secret token without a comma",
        "time,ground_acc\x07,theta",
        "a,b,c",
        "time," + "y" * 3000,
    ],
    ids=["colons", "no-comma", "control-character", "no-known-name", "very-long"],
)
def test_a_first_line_that_is_not_a_header_is_not_echoed(tmp_path, first):
    path = tmp_path / "f.csv"
    path.write_text(first + "\n1,2,3\n")
    with pytest.raises(DataFileError) as e:
        read_csv_si(path, {"time": "time", "ground_acc": "acceleration", "theta": "angle"})
    msg = str(e.value).replace(str(tmp_path), "")  # (the temporary folder's name may hold "root")
    assert "the first line is not a CSV header with a `" in msg and f"({len(first)} characters" in msg
    assert first not in msg and "root" not in msg and "secret" not in msg and "yyyy" not in msg


# ---------------------------------------------------------------------------- 3. one input rule for every reader
def test_every_reader_needs_the_same_number_of_samples(tmp_path):
    rule = f"only 2 samples; a record needs at least {MIN_RECORD_SAMPLES}"
    (tmp_path / "s").mkdir()
    (tmp_path / "s" / "short.csv").write_text("time,ground_acc\n0,0.1\n0.01,0.2\n")
    (tmp_path / "s" / "s.toml").write_text(SCENARIO.format(motions='record = "short.csv"'))
    with pytest.raises(ScenarioError, match=rule):
        load_scenario(tmp_path / "s" / "s.toml")
    folder = make_campaign(
        tmp_path / "camp",
        {"x": "records/short.csv"},
        {"records/short.csv": "time,ground_acc,theta\n0,0.1,0\n0.01,0.2,0\n"},
    )
    assert rule in skipped_message(load_campaign(folder), "x")


def test_a_declared_unit_is_checked_after_conversion(tmp_path):
    assert DECLARED_ACC_CEILING > 6 * G > PLAUSIBLE_ACC  # the ASU tests' unfiltered spikes reach 5.9 g
    spike = tmp_path / "spike.csv"
    spike.write_text(record_csv(peak=5.9 * G, header="time [s],ground_acc [m/s^2],theta [rad]"))
    assert read_csv_si(spike, {"ground_acc": "acceleration"}).values[0].max() > 5.8 * G
    huge = tmp_path / "huge.csv"
    huge.write_text(record_csv(peak=1e6, header="time [s],ground_acc [m/s^2],theta [rad]"))
    with pytest.raises(
        DataFileError,
        match=r"huge\.csv line \d+, column `ground_acc`: peak [\d.e+]+ m/s\^2 .* "
        r"declared unit m/s\^2, is above 50 g",
    ):
        read_csv_si(huge, {"time": "time", "ground_acc": "acceleration"})
    in_g = tmp_path / "in_g.csv"  # m/s^2 values declared in g
    in_g.write_text(record_csv(peak=60.0, header="time,ground_acc [g],theta"))
    with pytest.raises(DataFileError, match="column `ground_acc`: .*declared unit g"):
        GroundMotion.from_csv(in_g)
    folder = make_campaign(tmp_path / "camp", {"x": "records/huge.csv"}, {"records/huge.csv": huge.read_text()})
    assert "is above 50 g" in skipped_message(load_campaign(folder), "x")
    at2 = tmp_path / "big.AT2"
    at2.write_text(
        "PEER\nUNITS OF G\nx\nNPTS= 20, DT= 0.01 SEC\n"
        + "0.1 0.2 0.3 0.4 0.5\n" * 2
        + "0.1 0.2 70.0 0.4 0.5\n"
        + "0.1 0.2 0.3 0.4 0.5\n"
    )
    with pytest.raises(DataFileError, match=r"big\.AT2 line 7: peak .* = 70 g, read in the declared unit g"):
        GroundMotion.from_at2(at2)


BOOM = 'x = 1\nraise RuntimeError("boom")\n'
SYNTAX = "x = 1\ndef broken(:\n    pass\n"


@pytest.mark.parametrize(
    "code, expect",
    [(BOOM, "line 2: raises RuntimeError when imported: boom"), (SYNTAX, "line 2: syntax error")],
    ids=["raises", "syntax"],
)
def test_a_bad_plugin_is_exit_2_naming_the_file(tmp_path, capsys, code, expect):
    plugin = tmp_path / "bad_plugin.py"
    plugin.write_text(code)
    assert main(["run", "free-vibration", "--plugin", str(plugin), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "bad_plugin.py" in err and expect in err, err
    assert "unexpected" not in err and "Traceback" not in err
    (tmp_path / "s.toml").write_text('plugins = ["bad_plugin.py"]\n' + SCENARIO.format(motions='record = "elcentro"'))
    with pytest.raises(ScenarioError, match=rf"s\.toml line 1: plugin 'bad_plugin\.py': .*bad_plugin\.py.*{expect}"):
        load_scenario(tmp_path / "s.toml")
    assert main(["run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "bad_plugin.py" in err and expect in err, err


@pytest.mark.parametrize("name", RUN_FILES)
def test_a_users_own_file_in_out_is_not_overwritten(tmp_path, capsys, name):
    out = tmp_path / "out"
    out.mkdir()
    (out / name).write_text('{"mine": true}' if name.endswith(".json") else "my own data")
    with pytest.raises(
        OutputPathError,
        match=rf"{name!r} inside it is not from a housner run .*another --out or "
        "remove the file",
    ):
        check_output_dir(out, "--out", files=RUN_FILES)
    assert main(["run", "free-vibration", "--jobs", "1", "-q", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and str(out) in err and repr(name) in err, err
    assert (out / name).read_text() in ('{"mine": true}', "my own data")  # untouched


def test_a_previous_runs_files_may_be_replaced(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    for name in RUN_FILES:
        (out / name).write_text("old")
    (out / "run.json").write_text(json.dumps({"scenario": {"name": "x"}, "provenance": provenance()}))
    assert check_output_dir(out, "--out", files=RUN_FILES) == out
    # only a caller that writes a run directory (its files name a manifest) is held to this
    (out / "run.json").unlink()
    assert check_output_dir(out, "run directory", files=("report.html",)) == out
