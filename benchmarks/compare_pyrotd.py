"""RotD50 of rockslide against pyrotd 0.6.1 on the paper's real pairs -> results/compare_pyrotd.md.

Every figure docs/two-components.md quotes for this comparison comes from this script. For each
pair of horizontal components (Kobe JMA 1995 N-S/E-W, PEER RSN1106; Mexico SCT1 1985 N-S/E-W) and
each period of a log-spaced grid, it computes RotD50 of 5 %-damped pseudo-spectral acceleration
(the median over the 180 rotation angles) with `rockslide.core.intensity.rotd_peaks` and with
``pyrotd.calc_rotated_spec_accels`` (angles 0..179 deg, its default "optimized" method), and
reports the ratio rockslide / pyrotd - 1 per period band (smallest and largest over the periods
of the band) and per period.

The two differ by definition, not by a mistake of either:

- rockslide takes the record as linear between samples and integrates the oscillator exactly
  over each step (Nigam and Jennings), with sub-steps for short periods;
- pyrotd works in the frequency domain: the record's FFT (no padding: circular) times the
  oscillator's transfer function. Where the oscillator's frequency is above a fifth of the
  Nyquist frequency it pads the spectrum with zeros, i.e. it takes the record as band-limited
  (sinc interpolation between samples). Short periods therefore see a different input
  between samples; long periods see a periodic record, whose response at the start carries the
  free vibration left at the end of the record.

Needs pyrotd (``pip install pyrotd==0.6.1``; not a dependency of rockslide) and the paper's
records (``$ROCKSLIDE_RECORDS``, else ``../shared/records``).

Usage: python benchmarks/compare_pyrotd.py [--out results/compare_pyrotd.md]
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from rockslide.core import intensity  # noqa: E402
from rockslide.io.records import load_record  # noqa: E402

G = 9.80665                    # [m/s^2]
DAMPING = 0.05
PERIODS = np.round(np.geomspace(0.01, 5.0, 28), 4)      # [s]
BANDS = ((0.0, 0.05), (0.05, 0.3), (0.3, 1.0), (1.0, 3.0), (3.0, 5.0))  # [s], each (low, high]


def records_dir() -> Path:
    env = os.environ.get("ROCKSLIDE_RECORDS")
    for folder in ([Path(env)] if env else []) + [REPO.parent / "shared" / "records"]:
        if folder.is_dir():
            return folder
    sys.exit("needs the paper's records: set ROCKSLIDE_RECORDS or place them in ../shared/records")


def pairs(folder: Path):
    """(name, a1 [g], a2 [g], dt [s]) of each pair."""
    ns = load_record(folder / "kobe_jma_1995_ns_peer_rsn1106_kjm000.at2")
    ew = load_record(folder / "kobe_jma_1995_ew_peer_rsn1106_kjm090.at2")
    yield "Kobe JMA 1995 (RSN1106, N-S / E-W)", ns.data / G, ew.data / G, ns.dt
    mexico = folder / "mexico_sct1_1985_ns_ew_ud_g_dt002.txt"
    a = load_record(mexico, units="g", time_column=1, column=2)
    b = load_record(mexico, units="g", time_column=1, column=3)
    yield "Mexico SCT1 1985 (N-S / E-W)", a.data / G, b.data / G, a.dt


def compare(a1, a2, dt):
    import pyrotd

    ours = np.array([np.median(intensity.rotd_peaks(a1, a2, dt, "sa", float(p), DAMPING)) for p in PERIODS])
    frequencies = 1.0 / PERIODS
    rows = pyrotd.calc_rotated_spec_accels(dt, a1, a2, frequencies, DAMPING, percentiles=[50])
    by_frequency = {float(row["osc_freq"]): float(row["spec_accel"]) for row in rows}
    return ours, np.array([by_frequency[float(f)] for f in frequencies])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REPO / "results" / "compare_pyrotd.md")
    args = parser.parse_args(argv)
    import pyrotd

    lines = ["# RotD50 Sa (5 %): rockslide against pyrotd", "",
             f"Measured by `benchmarks/compare_pyrotd.py` on {datetime.date.today().isoformat()} "
             f"(pyrotd {pyrotd.__version__}, numpy {np.__version__}, Python {platform.python_version()}). "
             "Ratio = rockslide / pyrotd - 1, in %.", "",
             "The difference is one of definition: rockslide takes the record as linear between samples, "
             "pyrotd as band-limited (its FFT, padded with zeros in frequency at short periods); pyrotd's FFT "
             "is not padded in time, so at long periods its record is periodic (circular).", ""]
    per_period = []
    lines += ["| pair | " + " | ".join(f"{lo:g} < T <= {hi:g} s" for lo, hi in BANDS) + " |",
              "|---|" + "---|" * len(BANDS)]
    for name, a1, a2, dt in pairs(records_dir()):
        ours, theirs = compare(a1, a2, dt)
        ratio = 100.0 * (ours / theirs - 1.0)
        cells = []
        for lo, hi in BANDS:
            inside = (PERIODS > lo) & (PERIODS <= hi)
            cells.append(f"{ratio[inside].min():+.1f} to {ratio[inside].max():+.1f}")
        lines.append(f"| {name} (dt {dt:g} s) | " + " | ".join(cells) + " |")
        per_period.append((name, ours, theirs, ratio))
    for name, ours, theirs, ratio in per_period:
        lines += ["", f"## {name}", "", "| T [s] | rockslide [g] | pyrotd [g] | ratio - 1 [%] |", "|---|---|---|---|"]
        lines += [f"| {p:g} | {o:.4f} | {t:.4f} | {r:+.2f} |" for p, o, t, r in zip(PERIODS, ours, theirs, ratio,
                                                                                   strict=True)]
    args.out.write_text("\n".join(lines) + "\n")
    print("\n".join(lines[:12 + len(per_period)]))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
