"""Malformed input through the public command: one line, the culprit named, a non-zero exit, never a traceback.

Each case builds its input in a fresh folder and runs ``housner ...`` in this
process (``housner.cli.main``), a few as a real subprocess. The inputs cover
scenario files, campaign files and their CSV records, command-line arguments
and output paths. Nearly all fail before any simulation; the few that need a
run directory share one, made once.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
from shared import run_housner

from housner.cli import main
from housner.scenarios.catalogue.scenario import load_scenario

ROOT = Path(__file__).resolve().parent.parent

FV = """name = "bad"
[specimen]
preset = "bachmann2017"
[motions]
source = "free_vibration"
theta0_over_alpha = [0.5]
duration = 1.0
dt = 0.002
[engines]
names = ["housner"]
"""

RDK = """name = "bad"
[specimen]
preset = "bachmann2017"
[motions]
source = "rdk"
record = "elcentro"
n = 2
seed = 1
prototype_height = 5.0
amplitude = 1.0
[engines]
names = ["housner"]
"""

PULSES = """name = "bad"
[specimen]
preset = "bachmann2017"
[motions]
source = "pulses"
pulse = "symmetric_ricker"
omega_ratio = [2.0, 4.0]
accel_ratio = [1.5]
[engines]
names = ["housner"]
"""

CAMPAIGN = """name = "bad campaign"
[specimen]
height = 0.5
width = 0.075
depth = 0.4
mass = 3.94
p = 4.8883
[[record]]
id = "gm01"
kind = "ground_motion"
file = "records/gm01.csv"
"""


def good_csv(n: int = 400) -> str:
    t = np.arange(n) * 0.002
    acc = 0.5 * np.sin(2 * np.pi * 3 * t)
    return "time,ground_acc,theta\n" + "".join(f"{a:.4f},{b:.6e},0.0\n" for a, b in zip(t, acc, strict=True))


@dataclass
class Case:
    """One malformed input: ``build(tmp) -> argv``; ``expect``: substrings the error must hold."""

    id: str
    build: object
    expect: list = field(default_factory=list)
    status: int | None = 2  # None: any non-zero status
    xfail: str | None = None


def scenario(base: str, old: str | None = None, new: str = "", *, raw: bytes | None = None):
    """A scenario file made from ``base`` with ``old`` replaced by ``new`` (or the raw bytes)."""

    def build(tmp: Path) -> list[str]:
        path = tmp / "scen.toml"
        if raw is not None:
            path.write_bytes(raw)
        else:
            assert old is None or old in base, old
            path.write_text(base.replace(old, new) if old is not None else base + new)
        return ["run", str(path), "--jobs", "1", "--no-report", "-q", "--out", str(tmp / "out")]

    return build


def argv(*args: str):
    def build(tmp: Path) -> list[str]:
        return [a.replace("{tmp}", str(tmp)) for a in args]

    return build


def with_files(files: dict[str, str | bytes], *args: str):
    """Write ``files`` (relative path -> text or bytes; a trailing / makes a directory) then run ``args``."""

    def build(tmp: Path) -> list[str]:
        for rel, content in files.items():
            p = tmp / rel
            if rel.endswith("/"):
                p.mkdir(parents=True, exist_ok=True)
                continue
            p.parent.mkdir(parents=True, exist_ok=True)
            if isinstance(content, bytes):
                p.write_bytes(content)
            else:
                p.write_text(content.replace("{tmp}", str(tmp)))
        return [a.replace("{tmp}", str(tmp)) for a in args]

    return build


def campaign(toml: str | bytes, csv: str | bytes | None = None, *extra: str):
    files = {"camp/campaign.toml": toml}
    if csv is not None:
        files["camp/records/gm01.csv"] = csv
    return with_files(files, "diagnose", "{tmp}/camp", "-q", *extra)


def camp_csv(csv: str | bytes):
    return campaign(CAMPAIGN, csv)


S = "scen.toml"

CASES = [
    # ---------------------------------------------------------------- arguments
    Case("jobs-negative", argv("run", "free-vibration", "--jobs", "-2"), ["--jobs", "positive"]),
    Case("jobs-zero", argv("run", "free-vibration", "--jobs", "0"), ["--jobs"]),
    Case("jobs-text", argv("run", "free-vibration", "--jobs", "many"), ["--jobs", "many"]),
    Case("n-motions-zero", argv("run", "elcentro", "--n-motions", "0"), ["--n-motions"]),
    Case("n-motions-negative", argv("run", "elcentro", "--n-motions", "-5"), ["--n-motions"]),
    Case("n-motions-float", argv("run", "elcentro", "--n-motions", "2.5"), ["--n-motions", "2.5"]),
    Case("seed-negative", argv("run", "elcentro", "--seed", "-1"), ["--seed", "non-negative"]),
    Case("seed-text", argv("run", "elcentro", "--seed", "abc"), ["--seed", "abc"]),
    Case("n-motions-fixed-set", argv("run", "free-vibration", "--n-motions", "5"), ["--n-motions", "free-vibration"]),
    Case("seed-fixed-set", argv("run", "ricker-spectrum", "--seed", "3"), ["--seed", "ricker-spectrum"]),
    Case("engine-unknown", argv("run", "free-vibration", "--engines", "mujok"), ["--engines", "mujok", "mujoco"]),
    Case("engines-empty", argv("run", "free-vibration", "--engines", ","), ["--engines"]),
    Case("scenario-missing-arg", argv("run"), ["scenario"]),
    Case("scenario-unknown", argv("run", "elcentr"), ["elcentr", "did you mean 'elcentro'"]),
    Case("command-unknown", argv("simulate"), ["simulate"]),
    Case("option-unknown", argv("run", "elcentro", "--bogus"), ["--bogus"]),
    Case("train-fraction-high", argv("diagnose", "{tmp}", "--train-fraction", "1.5"), ["--train-fraction"]),
    Case("train-fraction-text", argv("diagnose", "{tmp}", "--train-fraction", "half"), ["--train-fraction"]),
    Case("max-effects-negative", argv("diagnose", "{tmp}", "--max-effects", "-1"), ["--max-effects"]),
    Case("diagnose-seed-negative", argv("diagnose", "{tmp}", "--seed", "-3"), ["--seed"]),
    Case(
        "effect-unknown",
        with_files({"c/campaign.toml": CAMPAIGN}, "diagnose", "{tmp}/c", "--effects", "slidding"),
        ["--effects", "slidding", "did you mean 'sliding'"],
    ),
    Case(
        "add-unknown",
        with_files({"c/campaign.toml": CAMPAIGN}, "diagnose", "{tmp}/c", "--add", "rotational_dampign"),
        ["--add", "rotational_dampign"],
    ),
    Case("target-r-high", argv("tune", "mujoco", "--target-r", "1.5"), ["--target-r"]),
    Case("amplitudes-text", argv("tune", "mujoco", "--amplitudes", "0.2,abc"), ["--amplitudes", "abc"]),
    Case("amplitudes-out-of-range", argv("tune", "mujoco", "--amplitudes", "0.5,1.2"), ["--amplitudes", "1.2"]),
    Case("tune-engine-unknown", argv("tune", "mujok", "--defaults-only", "-q"), ["mujok"]),
    Case(
        "scheduler-bad-scheme",
        argv("run", "free-vibration", "--engines", "housner", "--out", "{tmp}/o", "--scheduler", "foo://x:1"),
        ["foo://x:1", "scheme"],
        status=1,
    ),
    Case(
        "scheduler-closed-port",
        argv("run", "free-vibration", "--engines", "housner", "--out", "{tmp}/o", "--scheduler", "tcp://127.0.0.1:9"),
        ["tcp://127.0.0.1:9"],
        status=1,
    ),
    # ---------------------------------------------------------------- output paths
    Case(
        "out-is-a-file",
        with_files({"afile": "x"}, "run", "free-vibration", "--engines", "housner", "--out", "{tmp}/afile"),
        ["--out", "afile", "file"],
    ),
    Case(
        "out-under-a-file",
        with_files({"afile": "x"}, "run", "free-vibration", "--engines", "housner", "--out", "{tmp}/afile/run"),
        ["--out", "afile/run"],
    ),
    Case(
        "out-in-proc",
        argv("run", "free-vibration", "--engines", "housner", "--out", "/proc/housner-run"),
        ["--out", "/proc/housner-run"],
    ),
    Case(
        "out-holds-a-directory-named-like-a-result",
        with_files({"o/results.parquet/": ""}, "run", "free-vibration", "--engines", "housner", "--out", "{tmp}/o"),
        ["results.parquet", "directory"],
    ),
    Case(
        "out-report-html-is-a-directory",
        with_files({"o/report.html/": ""}, "run", "free-vibration", "--engines", "housner", "--out", "{tmp}/o"),
        ["report.html"],
    ),
    Case("report-run-dir-missing", argv("report", "{tmp}/nothing"), ["nothing"]),
    Case("report-run-dir-is-a-file", with_files({"afile": "x"}, "report", "{tmp}/afile"), ["afile"]),
    Case("report-run-dir-empty", with_files({"empty/": ""}, "report", "{tmp}/empty"), ["empty", "results.parquet"]),
    Case(
        "report-results-corrupt",
        with_files({"r/results.parquet": "not parquet", "r/run.json": "{}"}, "report", "{tmp}/r"),
        ["r"],
    ),
    Case("report-out-is-a-directory", argv("report", "{run}", "--out", "{tmp}"), ["--out", "directory"]),
    Case(
        "report-out-under-a-file",
        with_files({"afile": "x"}, "report", "{run}", "--out", "{tmp}/afile/r.html"),
        ["--out", "afile/r.html", "afile is a file"],
    ),
    Case(
        "diagnose-report-is-a-directory",
        with_files({"c/campaign.toml": CAMPAIGN, "d/": ""}, "diagnose", "{tmp}/c", "--report", "{tmp}/d"),
        ["--report", "directory"],
    ),
    Case(
        "diagnose-json-is-a-directory",
        with_files({"c/campaign.toml": CAMPAIGN, "d/": ""}, "diagnose", "{tmp}/c", "--json", "{tmp}/d"),
        ["--json", "directory"],
    ),
    Case(
        "diagnose-json-under-a-file",
        with_files({"c/campaign.toml": CAMPAIGN, "f": "x"}, "diagnose", "{tmp}/c", "--json", "{tmp}/f/d.json"),
        ["--json", "f/d.json"],
    ),
    Case(
        "diagnose-report-trailing-slash",
        with_files({"c/campaign.toml": CAMPAIGN}, "diagnose", "{tmp}/c", "--report", "{tmp}/newdir/"),
        ["--report", "slash"],
    ),
    Case("tune-json-is-a-directory", argv("tune", "mujoco", "--json", "{tmp}", "--defaults-only"), ["--json"]),
    # ---------------------------------------------------------------- scenario files
    Case("toml-syntax", scenario(FV, 'source = "free_vibration"', "source = "), [S, "line 5", "invalid TOML"]),
    Case("toml-not-utf8", scenario(FV, raw=FV.encode().replace(b"bad", b"b\xe9d")), [S, "line 1", "UTF-8"]),
    Case("scenario-is-a-directory", argv("run", "{tmp}"), ["directory", "scenario"]),
    Case("scenario-file-missing", argv("run", "{tmp}/none.toml"), ["none.toml", "does not exist"]),
    Case("rdk-n-zero", scenario(RDK, "n = 2", "n = 0"), [S, "line 7", "'n'", "positive"]),
    Case("rdk-n-negative", scenario(RDK, "n = 2", "n = -3"), [S, "'n'"]),
    Case("rdk-n-float", scenario(RDK, "n = 2", "n = 2.5"), [S, "'n'", "int"]),
    Case("rdk-n-bool", scenario(RDK, "n = 2", "n = true"), [S, "'n'"]),
    Case("rdk-seed-negative", scenario(RDK, "seed = 1", "seed = -1"), [S, "line 8", "'seed'", "non-negative"]),
    Case("rdk-amplitude-nan", scenario(RDK, "amplitude = 1.0", "amplitude = nan"), [S, "'amplitude'", "finite"]),
    Case("rdk-amplitude-inf", scenario(RDK, "amplitude = 1.0", "amplitude = inf"), [S, "'amplitude'"]),
    Case("rdk-amplitude-zero", scenario(RDK, "amplitude = 1.0", "amplitude = 0.0"), [S, "'amplitude'"]),
    Case("rdk-amplitude-text", scenario(RDK, "amplitude = 1.0", 'amplitude = "big"'), [S, "'amplitude'"]),
    Case("rdk-record-unknown", scenario(RDK, '"elcentro"', '"kobe"'), [S, "kobe", "record"]),
    Case("rdk-S-zero", scenario(RDK, "prototype_height = 5.0", "S = 0.0"), [S, "'S'"]),
    Case("rdk-prototype-negative", scenario(RDK, "prototype_height = 5.0", "prototype_height = -5.0"), [S]),
    Case("key-unknown", scenario(FV, "duration = 1.0", "duraton = 1.0"), [S, "duraton", "did you mean 'duration'"]),
    Case("table-unknown", scenario(FV, None, "[analyses]\nreference = 'housner'\n"), [S, "line 11", "analyses"]),
    Case("motions-missing", scenario("name = 'x'\n[specimen]\npreset = 'bachmann2017'\n"), [S, "[motions]"]),
    Case("specimen-missing", scenario("[motions]\nsource = 'free_vibration'\ntheta0_over_alpha = [0.5]\n"), [S]),
    Case("source-unknown", scenario(FV, '"free_vibration"', '"rdkk"'), [S, "rdkk", "did you mean 'rdk'"]),
    Case("theta0-empty", scenario(FV, "[0.5]", "[]"), [S, "theta0_over_alpha"]),
    Case("theta0-above-one", scenario(FV, "[0.5]", "[1.5]"), [S, "theta0_over_alpha", "(0, 1)"]),
    Case("theta0-text", scenario(FV, "[0.5]", '["a"]'), [S, "theta0_over_alpha"]),
    Case("dt-zero", scenario(FV, "dt = 0.002", "dt = 0.0"), [S, "'dt'"]),
    Case("dt-negative", scenario(FV, "dt = 0.002", "dt = -0.01"), [S, "'dt'"]),
    Case("duration-nan", scenario(FV, "duration = 1.0", "duration = nan"), [S, "'duration'"]),
    Case("dt-above-duration", scenario(FV, "dt = 0.002", "dt = 2.0"), [S, "'dt'", "duration"]),
    Case(
        "specimen-mass-negative",
        scenario(FV, 'preset = "bachmann2017"', "height = 1.0\nwidth = 0.2\ndepth = 1.0\nmass = -1.0"),
        [S, "mass", "positive"],
    ),
    Case("specimen-preset-unknown", scenario(FV, '"bachmann2017"', '"eth"'), [S, "eth", "preset"]),
    Case("specimen-height-text", scenario(FV, 'preset = "bachmann2017"', 'height = "tall"'), [S, "height"]),
    Case("engine-name-unknown", scenario(FV, '["housner"]', '["mujok"]'), [S, "mujok", "did you mean 'mujoco'"]),
    Case("engine-names-empty", scenario(FV, '["housner"]', "[]"), [S, "names"]),
    Case("engine-names-number", scenario(FV, '["housner"]', "[1]"), [S, "names"]),
    Case("engine-names-nested", scenario(FV, '["housner"]', '[["housner"]]'), [S, "names"]),
    Case("engine-table-unknown", scenario(FV, None, "[engines.mujok]\ntimestep = 0.001\n"), [S, "mujok"]),
    Case(
        "engine-setting-refused",
        scenario(FV, '["housner"]', '["mujoco"]\n[engines.mujoco]\ntimestep = -1.0'),
        [S, "[engines.mujoco]", "timestep"],
    ),
    Case(
        "engine-setting-unknown",
        scenario(FV, None, "[engines.housner]\nsubstep = 3\n"),
        [S, "[engines.housner]", "substep", "did you mean 'substeps'"],
    ),
    Case("pulse-grid-no-num", scenario(PULSES, "[2.0, 4.0]", "{ start = 1.0, stop = 2.0 }"), [S, "omega_ratio"]),
    Case("pulse-grid-num-zero", scenario(PULSES, "[2.0, 4.0]", "{ start = 1.0, stop = 2.0, num = 0 }"), [S, "num"]),
    Case("pulse-grid-negative", scenario(PULSES, "[2.0, 4.0]", "[-1.0, 2.0]"), [S, "omega_ratio", "positive"]),
    Case("pulse-grid-text", scenario(PULSES, "[2.0, 4.0]", '["a"]'), [S, "omega_ratio"]),
    Case("pulse-unknown", scenario(PULSES, '"symmetric_ricker"', '"sinc"'), [S, "sinc", "pulse"]),
    Case("analysis-reference-unknown", scenario(FV, None, '[analysis]\nreference = "mujok"\n'), [S, "mujok"]),
    Case("analysis-percentile-key", scenario(FV, None, "[analysis]\npaper_percentiles = { 150 = 0.3 }\n"), [S, "150"]),
    Case(
        "analysis-percentile-value",
        scenario(FV, None, '[analysis]\npaper_percentiles = { 50 = "big" }\n'),
        [S, "paper_percentiles", "big"],
    ),
    Case("analysis-seed-spread", scenario(FV, None, "[analysis]\nseed_spread = -2\n"), [S, "seed_spread"]),
    Case("name-escapes", scenario(FV, 'name = "bad"', 'name = "../escape"'), [S, "line 1", "'name'"]),
    # ---------------------------------------------------------------- campaigns and their CSV records
    Case("campaign-missing", argv("diagnose", "{tmp}/none"), ["none", "campaign.toml"]),
    Case("campaign-dir-without-toml", with_files({"c/": ""}, "diagnose", "{tmp}/c"), ["c", "campaign.toml"]),
    Case("campaign-file-not-toml", with_files({"c.csv": "x"}, "diagnose", "{tmp}/c.csv"), ["c.csv"]),
    Case("campaign-toml-syntax", campaign(CAMPAIGN.replace("height = 0.5", "height = ")), ["campaign.toml", "line"]),
    Case("campaign-not-utf8", campaign(CAMPAIGN.encode().replace(b"bad", b"b\xe9d")), ["campaign.toml", "UTF-8"]),
    Case("campaign-no-specimen", campaign(CAMPAIGN.replace("[specimen]", "[specimn]")), ["campaign.toml", "specim"]),
    Case(
        "campaign-mass-negative", campaign(CAMPAIGN.replace("mass = 3.94", "mass = -3.94")), ["campaign.toml", "mass"]
    ),
    Case("campaign-mass-text", campaign(CAMPAIGN.replace("mass = 3.94", 'mass = "heavy"')), ["campaign.toml", "mass"]),
    Case("campaign-key-unknown", campaign(CAMPAIGN + 'colour = "red"\n'), ["campaign.toml", "colour"]),
    Case("campaign-record-kind", campaign(CAMPAIGN.replace('"ground_motion"', '"earthquake"')), ["earthquake"]),
    Case("campaign-record-no-file", campaign(CAMPAIGN.replace('file = "records/gm01.csv"\n', "")), ["file"]),
    Case("campaign-record-group", campaign(CAMPAIGN + "group = 3\n"), ["campaign.toml", "line 12", "'group'"]),
    Case(
        "campaign-record-list",
        campaign("record = [1, 2]\n" + CAMPAIGN.split("[[record]]")[0]),
        ["campaign.toml", "line 1", "record"],
    ),
    Case("campaign-no-records", campaign(CAMPAIGN.split("[[record]]")[0]), ["campaign.toml", "record"]),
    Case("campaign-csv-missing", campaign(CAMPAIGN), ["campaign.toml", "gm01"]),
    Case("campaign-csv-text-cell", camp_csv(good_csv().replace("0.0040,", "abc,", 1)), ["gm01.csv", "line"]),
    Case("campaign-csv-header", camp_csv(good_csv().replace("ground_acc", "acceleration", 1)), ["gm01.csv"]),
    Case("campaign-csv-empty", camp_csv(""), ["gm01.csv"]),
    Case("campaign-csv-one-column", camp_csv("time\n0.0\n0.002\n"), ["gm01.csv"]),
    Case("campaign-csv-not-utf8", camp_csv(b"time,ground_acc,theta\n0,0,\xff\n"), ["gm01.csv"]),
    Case("campaign-csv-nan", camp_csv(good_csv().replace(",0.0\n", ",nan\n", 3)), ["gm01.csv"]),
    Case("campaign-csv-time-backwards", camp_csv(good_csv().replace("0.0040,", "0.0010,", 1)), ["gm01.csv"]),
    Case("campaign-csv-unit-unknown", camp_csv(good_csv().replace("theta", "theta [furlongs]", 1)), ["gm01.csv"]),
]


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A real run directory (free vibration, analytic engine, one release) for the `report` cases."""
    base = tmp_path_factory.mktemp("run")
    path = base / "scen.toml"
    path.write_text(FV)
    os.environ.setdefault("HOUSNER_CACHE_DIR", str(base / "cache"))
    assert main(["run", str(path), "--jobs", "1", "--no-report", "-q", "--out", str(base / "out")]) == 0
    return base / "out"


@pytest.fixture(autouse=True)
def _private_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("HOUSNER_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("HOUSNER_DEBUG", raising=False)


def _params():
    out = []
    for c in CASES:
        marks = [pytest.mark.xfail(strict=False, reason=c.xfail)] if c.xfail else []
        out.append(pytest.param(c, id=c.id, marks=marks))
    return out


def test_there_are_enough_cases():
    assert len(CASES) >= 60
    assert len({c.id for c in CASES}) == len(CASES)


@pytest.mark.parametrize("case", _params())
def test_malformed_input_gives_one_line(case, tmp_path, capsys, request):
    args = case.build(tmp_path)
    if any("{run}" in a for a in args):
        run = request.getfixturevalue("run_dir")
        args = [a.replace("{run}", str(run)) for a in args]
    if case.id == "out-in-proc" and not Path("/proc").is_dir():
        pytest.skip("no /proc here")
    t0 = time.perf_counter()
    status = main(args)
    elapsed = time.perf_counter() - t0
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    assert status != 0
    if case.status is not None:
        assert status == case.status, err
    lines = [line for line in err.splitlines() if line.startswith("housner: error:")]
    assert len(lines) == 1, err
    for word in case.expect:
        assert word in lines[0], f"{word!r} not in: {lines[0]}"
    # Failing before the work: well under the time of one simulation batch (numba loading
    # alone takes ~4 s on 2 cores); 10 s leaves room for a loaded machine.
    assert elapsed < 10.0, f"{case.id} took {elapsed:.1f} s"


@pytest.mark.parametrize("base", [FV, RDK, PULSES], ids=["free_vibration", "rdk", "pulses"])
def test_the_unbroken_bases_load(base, tmp_path):
    """The cases above break these files one key at a time: unbroken, they are valid."""
    path = tmp_path / "scen.toml"
    path.write_text(base)
    scen = load_scenario(path)
    scen.check_engines()
    assert scen.n_motions >= 1


def test_unbroken_campaign_passes_the_checks_before_load(tmp_path, capsys):
    """The campaign base with a good CSV passes every check before the diagnosis
    (it then fails for a reason of its own: one record is too few to diagnose)."""
    build = campaign(CAMPAIGN, good_csv())
    status = main(build(tmp_path))
    err = capsys.readouterr().err
    assert status == 2 and "Traceback" not in err
    assert "at least 4" in err  # the diagnosis's own requirement, not a malformed input


# ---------------------------------------------------------------- the real command, in a subprocess
def _housner(*args: str, env_extra: dict | None = None) -> subprocess.CompletedProcess:
    return run_housner(*args, cwd=ROOT, env=dict(os.environ, **(env_extra or {})), timeout=120)


def test_subprocess_errors_are_one_line(tmp_path):
    (tmp_path / "afile").write_text("x")
    res = _housner("run", "free-vibration", "--out", str(tmp_path / "afile"))
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert res.stderr.strip() == f"housner: error: --out {tmp_path / 'afile'}: exists and is a file, not a directory"
    res = _housner("run", str(tmp_path))
    assert res.returncode == 2 and res.stderr.count("\n") == 1 and str(tmp_path) in res.stderr


def test_debug_shows_the_traceback(tmp_path):
    res = _housner("run", str(tmp_path / "none.toml"), env_extra={"HOUSNER_DEBUG": "1"})
    assert res.returncode == 2 and "Traceback" in res.stderr and "none.toml" in res.stderr.splitlines()[-1]
    res = _housner("--debug", "run", str(tmp_path / "none.toml"))
    assert res.returncode == 2 and "Traceback" in res.stderr


def test_version_and_help_list_the_registries():
    from housner.effects import available_effects, effect_class
    from housner.engines.base import ENGINES
    from housner.scenarios.catalogue.scenario import SCENARIOS

    res = _housner("--version")
    assert res.returncode == 0 and res.stdout.startswith("housner 0.") and "mujoco" in res.stdout
    # The package's own engines (other test modules register test engines in this process only).
    home = {n: spec.module for n, spec in ENGINES.items()}
    shipped = [n for n, m in home.items() if m.startswith("housner.engines.")]
    assert {"housner", "mujoco", "pybullet"} <= set(shipped)
    res = _housner("run", "--help")
    assert res.returncode == 0 and all(name in res.stdout for name in [*shipped, *SCENARIOS])
    assert "--allow-failures" in res.stdout and "exit status" in res.stdout
    res = _housner("diagnose", "--help")
    # the library's effects (other test modules load plugin effects in this process only)
    library = [n for n in available_effects() if effect_class(n).__module__.startswith("housner.")]
    assert res.returncode == 0 and all(name in res.stdout for name in library)


def test_missing_engine_package_is_one_line_naming_the_install(tmp_path):
    """An optional engine whose package is absent: exit 2, one line naming the install command, no run."""
    code = (
        "import sys; sys.modules['dartpy'] = None\n"  # as if dartpy were not installed
        "from housner.cli import main\n"
        f"sys.exit(main(['run', 'elcentro', '--engines', 'dart', '--out', {str(tmp_path / 'run')!r}, '-q']))"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and "engine 'dart' needs the dartpy package" in lines[0]
    assert "pip install -e '.[dart]'" in lines[0] and "Traceback" not in p.stderr
    assert not (tmp_path / "run" / "results.parquet").exists()


def test_the_command_runs_blas_on_one_thread_unless_told_otherwise():
    """OpenBLAS's threads fight numba's OpenMP threads for the cores: scipy's expm of the spectra's 4 x 4 matrices
    took 2.3 s instead of 1 ms on 2 cores. The command sets one BLAS thread before numpy loads, unless the user set
    a number."""
    import os

    code = "import housner.cli, os; print(os.environ['OPENBLAS_NUM_THREADS'])"
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert out.stdout.strip() == "1"
    env["OPENBLAS_NUM_THREADS"] = "3"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert out.stdout.strip() == "3"
