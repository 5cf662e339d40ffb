"""Write the small synthetic ASU data set of tests/test_asu_import.py, in the original repository's format.

Run ``python tests/data/asu_small/make_asu_small.py`` to rewrite the files beside it (the test checks that
they match this script). The files copy the format of the virtual-shake-robot project's
``data/Shake_Table_Response/Test###.txt``: tab-separated, one header row, 8 columns and a trailing tab,
CRLF line ends, numbers printed with 6 significant digits (some right-aligned with spaces), 800 Hz;
column 2 the table acceleration [g], column 6 the table displacement [V] (x 5.9797e-4 gives inches).

Signals, with a per-test scale ``k`` and accelerometer bias ``bias`` [g], t [s]:

- acceleration [g] = bias + k (0.1 sin 2pi 2t + 0.05 sin 2pi 7t) + 0.02 sin 2pi 60t + 0.05 sin 2pi 110t:
  a whole number of periods of each, so its mean is ``bias``; 60 Hz lies in the decimation filter's
  pass band (kept), 110 Hz in its stop band (removed to below 8e-5);
- displacement [m] = k 0.01 (1 - cos 2pi t) / 2: it starts and ends at rest, its peak velocity is k 0.01 pi.

``index.csv`` lists, in this order (not the test order): 12 (overturned), 11, 13 (no file, present = 0),
14 (no outcome), 15 (present = 1 but no file), 16 (a malformed file: 'n/a' at line 7, column 2) and 17
(its file in data/Shake_Table_Response/, as in the original repository). ``SP1.obj`` is a closed box,
0.2 x 0.3 x 0.6 m (z up), its corner at (1, 2, 0.5) m.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

RATE = 800  # [Hz]
VOLT = 5.9797e-4 * 0.0254  # [m/V]
#: test -> (scale k, bias [g], duration [s]) of the files with a signal.
SIGNALS = {11: (1.0, 0.012, 2.0), 12: (1.5, 0.018, 1.0), 17: (0.5, 0.015, 1.0)}
HEADER = "".join(f"Time [s] - Plot {i}\tAmplitude - Plot {i}\t" for i in range(4))
#: test, outcome (overturn_SP1), present, where its file is.
INDEX = [
    (12, "1", 1, "."),
    (11, "0", 1, "."),
    (13, "1", 0, None),
    (14, "", 1, "."),
    (15, "0", 1, None),
    (16, "1", 1, "."),
    (17, "0", 1, "data/Shake_Table_Response"),
]


def signals(k: float, bias: float, duration: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time [s], acceleration [g] and displacement [m] at 800 Hz."""
    t = np.arange(round(duration * RATE)) / RATE
    s = lambda f: np.sin(2 * np.pi * f * t)  # noqa: E731
    acc = bias + k * (0.1 * s(2) + 0.05 * s(7)) + 0.02 * s(60) + 0.05 * s(110)
    disp = k * 0.01 * (1 - np.cos(2 * np.pi * t)) / 2
    return t, acc, disp


def _txt(t: np.ndarray, acc: np.ndarray, volts: np.ndarray) -> str:
    lines = [HEADER]
    for i, (ti, a, v) in enumerate(zip(t, acc, volts, strict=True)):
        ay, vy = 0.01 * np.sin(2 * np.pi * 3 * ti), -20 + 0.5 * np.sin(2 * np.pi * ti)
        cells = [f"{x:g}" for x in (ti, a, ti, ay, ti, v, ti, vy)]
        if i % 97 == 13:  # as in the original files, now and then a cell right-aligned with spaces
            cells[4] = f"{cells[4]:>14}"
        lines.append("\t".join(cells) + "\t")
    return "\r\n".join(lines) + "\r\n"


def write(folder: Path) -> list[Path]:
    """Write the data set into ``folder``; the files written."""
    folder = Path(folder)
    out = []
    rows = ["test,date,record,PGV_over_PGA_s,scaled_PGA_g,overturn_SP1,source_path,present"]
    for test, outcome, present, where in INDEX:
        name = f"Test{test:03d}.txt"
        rows.append(f"{test},20210621,RSN0_SYNTHETIC,0.05,0.2,{outcome},data/Shake_Table_Response/{name},{present}")
        if where is None:
            continue
        path = folder / where / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if test in SIGNALS:
            t, acc, disp = signals(*SIGNALS[test])
            text = _txt(t, acc, disp / VOLT)
        else:  # 40 samples of a still table; test 16's has 'n/a' at line 7, column 2
            t = np.arange(40) / RATE
            text = _txt(t, np.full(40, 0.015), np.zeros(40))
            if test == 16:
                lines = text.split("\r\n")
                cells = lines[6].split("\t")
                cells[1] = "n/a"
                lines[6] = "\t".join(cells)
                text = "\r\n".join(lines)
        path.write_bytes(text.encode())
        out.append(path)
    (folder / "index.csv").write_text("\n".join(rows) + "\n")
    out.append(folder / "index.csv")
    v = np.array([[x, y, z] for z in (0.5, 1.1) for y in (2.0, 2.3) for x in (1.0, 1.2)])  # z-major corners
    quads = [(1, 3, 4, 2), (5, 6, 8, 7), (1, 2, 6, 5), (3, 7, 8, 4), (1, 5, 7, 3), (2, 4, 8, 6)]  # outward
    obj = [f"v {x:g} {y:g} {z:g}" for x, y, z in v]
    obj += [f"f {a} {b} {c}\nf {a} {c} {d}" for a, b, c, d in quads]
    (folder / "SP1.obj").write_text("# box 0.2 x 0.3 x 0.6 m, z up\n" + "\n".join(obj) + "\n")
    out.append(folder / "SP1.obj")
    return out


if __name__ == "__main__":
    for p in write(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parent):
        print(p)
