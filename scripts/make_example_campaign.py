#!/usr/bin/env python3
"""Write the shipped example campaign ``examples/campaigns/pivot-friction/`` (the tutorial's data).

Usage::

    python scripts/make_example_campaign.py            # rewrite examples/campaigns/pivot-friction/
    python scripts/make_example_campaign.py --check    # regenerate to a temporary folder, compare, exit 1 if changed
    python scripts/make_example_campaign.py --out /tmp/pf --n-ground 40

The records are made by the independent generator of the test suite,
``tests/independent_campaigns.py`` (written apart from the library: its own
Dormand-Prince integrator, ground motions and sensor model), with its
``pivot_friction`` case: the seed specimen of Bachmann et al. (2017) with a
Coulomb moment M_f = 0.09 N m at the pivot, sticking while the other moments
stay below it, and 0.8 mrad of Gaussian noise on theta. It is seeded
(``--seed``, 0): the same arguments write the same bytes.

So that the folder stays small (about 2.5 MB), the generator's full-precision
files are rewritten with fewer digits: time to 1 ms (exact at 500 Hz), ground
acceleration to 1e-3 m/s^2 and theta to 1e-5 rad (a 1/80 of the noise sigma),
trailing zeros dropped; and the free vibrations, which come to rest within
4.1 s, are kept to their first :data:`FV_KEEP` s. The README.md next to the
records says what the campaign is and what its truth is.
"""

from __future__ import annotations

import argparse
import filecmp
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
import independent_campaigns as ic  # noqa: E402  (the test generator, importable once tests/ is on the path)

#: Where the campaign is shipped.
DEFAULT_OUT = ROOT / "examples" / "campaigns" / "pivot-friction"
#: The generator's case and its truth (tests/independent_campaigns.py, CASES).
CASE = "pivot_friction"
#: Ground-motion records [-] and seed of the ground motions and the noise.
N_GROUND, SEED = 30, 0
#: Seconds of each free-vibration record kept (the block is at rest after 4.1 s) [s].
FV_KEEP = 6.0
#: Decimals written: time [s], ground_acc [m/s^2], theta [rad].
DECIMALS = {"time": 3, "ground_acc": 3, "theta": 5}


def _num(x: float, decimals: int) -> str:
    """``x`` with ``decimals`` decimals, trailing zeros dropped ("-0" written "0")."""
    s = f"{x:.{decimals}f}"
    if "." in s:
        s = s.rstrip("0").rstrip(".")
    return "0" if s in ("-0", "") else s


def _rewrite(src: Path, dst: Path, keep: float | None) -> None:
    """Rewrite the record ``src`` (the generator's time,ground_acc,theta CSV) to ``dst`` with fewer digits."""
    a = np.loadtxt(src, delimiter=",", skiprows=1)
    if keep is not None:
        a = a[a[:, 0] < keep - 1e-9]
    d = DECIMALS
    rows = [f"{_num(t, d['time'])},{_num(g, d['ground_acc'])},{_num(th, d['theta'])}" for t, g, th in a]
    dst.write_text("time,ground_acc,theta\n" + "\n".join(rows) + "\n")


def _toml(info: dict, n_ground: int, seed: int) -> str:
    """campaign.toml: the generator's specimen and recording order, with a name and a description."""
    lines = [
        'name = "Synthetic shake-table campaign: a rocking block with an unknown loss"',
        f'description = "Made by tests/independent_campaigns.py (case {CASE}, {n_ground} ground motions, seed '
        f'{seed}) with scripts/make_example_campaign.py; see README.md"',
        "",
        "[specimen]",
        f"height = {ic.HEIGHT}   # 2H [m]",
        f"width = {ic.WIDTH}   # 2B [m], between the pivots",
        f"depth = {ic.DEPTH}   # [m]",
        f"mass = {ic.MASS}   # [kg]",
        f"p = {ic.P_STATED}   # [1/s], measured",
    ]
    for rid, kind, _i in ic.recording_order(n_ground):
        lines += ["", "[[record]]", f'id = "{rid}"', f'kind = "{kind}"', f'file = "records/{rid}.csv"']
    return "\n".join(lines) + "\n"


def _unit(decimals: int) -> str:
    """The last written digit's unit, 10^-decimals, as text ("0.001", "1e-5")."""
    return f"{10.0**-decimals:g}".replace("e-0", "e-")


def _readme(info: dict, n_ground: int, seed: int) -> str:
    truth = info["truth"]
    n_over = int(np.sum(info["overturned"]))
    over_ids = ", ".join(i for i, o in zip(info["gm_ids"], info["overturned"], strict=True) if o)
    i0 = truth.side(1)[2]
    d = DECIMALS
    return f"""# Example campaign: a rocking block with pivot friction

The data of the [tutorial](../../../docs/tutorial.md): a measurement campaign in the
[campaign format](../../../docs/reference/campaign-format.md) on which the plain Housner model
fails, and which a user's own effect, `examples/effects/pivot_friction.py`, explains.

**It is synthetic.** No shake table measured it: it was computed, so that its truth is known
and you can check the tutorial's answer.

## What is in it

- `campaign.toml`: the specimen (the seed block of Bachmann et al. 2017: 2H = {ic.HEIGHT} m,
  2B = {ic.WIDTH} m between the pivots, m = {ic.MASS} kg, measured p = {ic.P_STATED} 1/s) and
  {n_ground + 3} records in the order they were "measured": free vibration `fv01`, ground motions
  `gm001`-`gm{n_ground // 2:03d}`, `fv02`, `gm{n_ground // 2 + 1:03d}`-`gm{n_ground:03d}`, `fv03`.
- `records/*.csv`: `time` [s], `ground_acc` [m/s^2], `theta` [rad] at 500 Hz. Ground motions: 8 s
  (the last 1.5 s quiet), synthetic (Clough-Penzien filtered noise, half of them with a velocity
  pulse) scaled to a peak of 1.0-2.5 g tan(alpha). Free vibrations: released at rest from +0.75,
  -0.55 and +0.4 alpha, table still; kept for {FV_KEEP:g} s (the block is at rest after 4.1 s).
- The block overturns in {n_over} of the {n_ground} ground motions ({over_ids}).

## How it was made

```
python scripts/make_example_campaign.py            # writes this folder (seed {seed}, {n_ground} ground motions)
python scripts/make_example_campaign.py --check    # regenerates it and says whether it still matches
```

The physics is computed by `tests/independent_campaigns.py`, the test suite's second,
independent generator: it was written apart from the library (its own adaptive Dormand-Prince
integrator with event location, its own ground motions and sensor model) so that the library is
judged on data none of its own code produced. The script takes its `{CASE}` case and rounds what
it writes (time to {_unit(d["time"])} s, ground acceleration to {_unit(d["ground_acc"])} m/s^2,
theta to {_unit(d["theta"])} rad: an 80th of the noise).

## The truth

- Rigid block, Housner's impact (angular momentum kept about the landing corner: energy ratio
  r = {ic.R_HOUSNER:.4f} per impact), p = {ic.P_STATED} 1/s: the plain model's physics, plus
- **Coulomb friction at the pivot, M_f = {truth.pivot_moment:g} N m**: a moment -M_f sgn(theta') while the
  block rotates; when theta' = 0 it sticks while the moments of gravity and the table stay within
  +-M_f (so, from rest, it lifts off only once the table pushes M_f / (m H) =
  {truth.pivot_moment / (ic.MASS * ic.H_COM):.3f} m/s^2 beyond g tan(alpha)). Inertia about a pivot
  I0 = m g R / p^2 = {i0:.4f} kg m^2, so M_f / I0 = {truth.pivot_moment / i0:.3f} rad/s^2.
- Sensor: Gaussian noise of {ic.NOISE * 1e3:g} mrad on theta; no offset, no lag; the ground acceleration
  is written as the block felt it.

Nothing in the library's own effect list is this loss: its search finds no effect that
explains the campaign (`partly_explained`). With the example effect added by hand,

```
housner diagnose examples/campaigns/pivot-friction --plugin examples/effects/pivot_friction.py \\
    --add pivot_friction --effects none
```

the verdict is `explained`, with M_f fitted to about {truth.pivot_moment:g} N m and the held-out error falling
by more than 90 %. `tests/test_example_campaign.py` checks this on every test run.
"""


def write(out: Path, n_ground: int = N_GROUND, seed: int = SEED) -> dict:
    """Write the example campaign to ``out`` (replacing its campaign.toml, records/ and README.md)."""
    out = Path(out)
    with tempfile.TemporaryDirectory() as tmp:
        info = ic.write_campaign(Path(tmp) / "full", CASE, n_ground=n_ground, seed=seed)
        if (out / "records").exists():
            shutil.rmtree(out / "records")
        (out / "records").mkdir(parents=True)
        for src in sorted((Path(tmp) / "full" / "records").glob("*.csv")):
            _rewrite(src, out / "records" / src.name, FV_KEEP if src.name.startswith("fv") else None)
    (out / "campaign.toml").write_text(_toml(info, n_ground, seed))
    (out / "README.md").write_text(_readme(info, n_ground, seed))
    return info


def _same(a: Path, b: Path) -> list[str]:
    """Files that differ between the campaign folders ``a`` and ``b`` (missing on either side included)."""
    names = {p.relative_to(a).as_posix() for p in a.rglob("*") if p.is_file()}
    names |= {p.relative_to(b).as_posix() for p in b.rglob("*") if p.is_file()}
    return sorted(
        n for n in names if not ((a / n).is_file() and (b / n).is_file() and filecmp.cmp(a / n, b / n, shallow=False))
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT, help=f"campaign folder ({DEFAULT_OUT.relative_to(ROOT)})")
    ap.add_argument("--n-ground", type=int, default=N_GROUND, help=f"ground-motion records ({N_GROUND})")
    ap.add_argument("--seed", type=int, default=SEED, help=f"seed of the motions and the noise ({SEED})")
    ap.add_argument("--check", action="store_true", help="regenerate to a temporary folder and compare with --out")
    args = ap.parse_args(argv)
    if args.check:
        with tempfile.TemporaryDirectory() as tmp:
            write(Path(tmp), args.n_ground, args.seed)
            diff = _same(Path(tmp), args.out)
        print(f"{args.out}: " + ("up to date" if not diff else f"{len(diff)} file(s) differ: {', '.join(diff[:5])}"))
        return 1 if diff else 0
    info = write(args.out, args.n_ground, args.seed)
    size = sum(p.stat().st_size for p in args.out.rglob("*") if p.is_file())
    n_rec = len(ic.recording_order(args.n_ground))
    print(
        f"wrote {args.out}: {n_rec} records, {size / 1e6:.2f} MB, "
        f"{int(np.sum(info['overturned']))} of {args.n_ground} ground motions overturn"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
