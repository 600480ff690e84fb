"""Reproduce the paper's results section: Table 1 and Figures 5 to 10 (``make table1``).

Each row of Table 1 is a case file in ``configs/table1/``. This module runs them on the paper's
records (found in the records directory), with the case's gravity (9.80665 m/s^2) and with
g = 9.8 m/s^2 (what papers of the time commonly used), checks each verdict's robustness
(`runner.verdict_robustness`: dt/2, mu +- 1 %), describes the motion as the paper does (the motion
before the rotation first passed alpha apart from the fall, model.md decision 4), checks the
paper's remarks, and writes ``table1.md``, ``table1.csv`` and ``fig05.png`` ... ``fig10.png``.
"""

from __future__ import annotations

import csv
import io
import math
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import interrupts, plots
from ..case import case_with, load_case
from ..core import criteria
from ..engine import prepare as runner
from ..errors import RecordError
from ..io.files import Staging, atomic_write, check_destination

PAPER_G = 9.8

# The paper's Table 1: figure, record, max horizontal and vertical acceleration [gal], mu,
# judgement of overturning, description; and the case file of the row.
PAPER_TABLE = (
    ("6(a)", "Mexico", 600.0, 172.8, 0.50, False, "Slip only", "fig06a-mu050"),
    ("6(b)", "Mexico", 600.0, 172.8, 0.52, True, "No rebound and slip is observed", "fig06b-mu052"),
    ("6(b)", "Mexico", 600.0, 172.8, 0.55, True, "The same as above", "fig06b-mu055"),
    ("7(a)", "Mexico", 800.0, 230.4, 0.50, False, "Slip only", "fig07a-mu050"),
    ("7(b)", "Mexico", 800.0, 230.4, 0.52, True, "No rebound and slip is observed", "fig07b-mu052"),
    ("7(b)", "Mexico", 800.0, 230.4, 0.55, True, "The same as above", "fig07b-mu055"),
    ("8(a)", "Hyogoken-nanbu", 600.0, 243.7, 0.50, False, "Slip only", "fig08a-mu050"),
    ("8(b)", "Hyogoken-nanbu", 600.0, 243.7, 0.52, False, "Liftoff-Slip interaction is observed", "fig08b-mu052"),
    ("8(c)", "Hyogoken-nanbu", 600.0, 243.7, 0.55, False, "No slip is observed. The body avoids overturning",
     "fig08c-mu055"),
    ("9(a)", "Hyogoken-nanbu", 800.0, 324.9, 0.50, False, "Slip only", "fig09a-mu050"),
    ("9(b)", "Hyogoken-nanbu", 800.0, 324.9, 0.52, False, "Liftoff-slip interaction is observed", "fig09b-mu052"),
    ("9(c)", "Hyogoken-nanbu", 800.0, 324.9, 0.55, True, "No slip is observed", "fig09c-mu055"),
    ("10(a)", "Hyogoken-nanbu", 800.0, 324.9, 0.52, False, "Reference for Fig.9(b) with no liftoff motions",
     "fig10a-mu052"),
    ("10(b)", "Hyogoken-nanbu", 800.0, 162.5, 0.52, False,
     "Reference for Fig.9(b) with half vertical accelerations", "fig10b-mu052"),
    ("10(c)", "Hyogoken-nanbu", 800.0, 649.8, 0.52, False,
     "Reference for Fig.9(b) with twice vertical accelerations", "fig10c-mu052"),
)

# What each description claims, as predicates on `Motion` (before the fall past alpha).
# "No rebound and slip is observed" is read as "neither rebound nor slip": the block lifts off and
# falls over without an impact and without slipping.
CLAIMS = {
    "Slip only": ("slip, no liftoff", lambda m: m.slip and not m.liftoff),
    "No rebound and slip is observed": ("no impact and no slip before the fall",
                                        lambda m: not m.rebound and not m.slip),
    "Liftoff-Slip interaction is observed": ("liftoff-slip interaction", lambda m: m.interaction),
    "Liftoff-slip interaction is observed": ("liftoff-slip interaction", lambda m: m.interaction),
    "No slip is observed. The body avoids overturning": ("no slip", lambda m: not m.slip),
    "No slip is observed": ("no slip before the fall", lambda m: not m.slip),
    "Reference for Fig.9(b) with no liftoff motions": ("no liftoff", lambda m: not m.liftoff),
}

RECORD_SOURCES = {
    "kobe": "PEER NGA-West2, RSN 1106 (Kobe 1995, station KJMA)",
    "mexico": "the SCT1 record of 19 Sep 1985 (Mexican strong-motion database / OpenSeismoMatlab)",
}


@dataclass
class Motion:
    """What happened before the rotation first passed alpha for good (the fall), and after."""

    slip: bool
    liftoff: bool
    interaction: bool
    rebound: bool
    interaction_times: list[float]
    fall_slip: bool      # slip during the fall (past alpha), which model.md expects whatever mu is


def motion(result) -> Motion:
    s = result.summary
    cutoff = s.fall_start_time if (s.overturned and s.fall_start_time is not None) else math.inf
    before = [e for e in result.events if e["time"] < cutoff]
    entered = {e["to"].decode() for e in before if e["from"] != e["to"]}
    causes = {e["cause"].decode() for e in before}
    after = {e["to"].decode() for e in result.events if e["time"] >= cutoff}
    return Motion(
        slip=bool(entered & {"SLIP", "ROCKSLIP"}),
        liftoff=bool(entered & {"ROCK", "ROCKSLIP"}),
        interaction="ROCKSLIP" in entered,
        rebound=bool(causes & {"impact", "liftoff-end"}),
        interaction_times=[float(e["time"]) for e in before
                           if e["to"] == b"ROCKSLIP" and e["from"] != b"ROCKSLIP"],
        fall_slip="ROCKSLIP" in after,
    )


@dataclass
class Row:
    figure: str
    record: str
    pga_h: float
    pga_v: float
    mu: float
    paper_overturned: bool
    paper_description: str
    name: str
    runs: dict = field(default_factory=dict)     # gravity -> dict


def required_records(configs: Path) -> list[str]:
    names = []
    for entry in PAPER_TABLE:
        case = load_case(configs / f"{entry[-1]}.yaml")
        for spec in (case.ground.horizontal, case.ground.vertical):
            if spec is not None and spec.file not in names:
                names.append(spec.file)
    return names


def check_records(configs: Path, records_dir: Path) -> None:
    """Stop with one line naming the first missing record and where to get it."""
    for name in required_records(configs):
        if not (records_dir / name).is_file():
            source = RECORD_SOURCES["kobe" if "kobe" in name else "mexico"]
            raise RecordError(f"the paper's record {name} is not in {records_dir}; get it from {source} "
                              "(docs/guide/records.md, 'The paper's records') and point --records-dir or "
                              "ROCKSLIDE_RECORDS at its folder")


def run_table(configs: Path, records_dir: Path, gravities=(None, PAPER_G), *,
              auto: bool = False) -> tuple[list[Row], dict]:
    """Run every row; ``None`` in ``gravities`` is the case file's own gravity; ``auto``: with
    ``solver.dt: auto`` and its default tolerance instead of the case files' 0.1 ms."""
    check_records(configs, records_dir)
    rows = [Row(*entry) for entry in PAPER_TABLE]
    results = {}
    for row in rows:
        base_case = load_case(configs / f"{row.name}.yaml")
        if auto:
            base_case = case_with(base_case, {"solver.dt": "auto"})
        for gravity in gravities:
            case = base_case if gravity is None else case_with(base_case, {"gravity": gravity})
            prepared = runner.prepare(case, records_dir, history=gravity is None)
            result = runner.simulate_prepared(prepared, progress=_check_signals)
            robustness = runner.verdict_robustness(prepared, result.summary.overturned, progress=_check_signals)
            key = case.gravity
            m = motion(result)
            s = result.summary
            row.runs[key] = {
                "overturned": s.overturned, "overturn_time": s.overturn_time, "direction": s.direction,
                "fall_start_time": s.fall_start_time, "max_rotation": s.max_rotation,
                "max_slip": s.max_slip, "residual_slip": s.residual_slip, "impacts": s.impacts,
                "motion": m, "robust": robustness["holds"], "variants": robustness["variants"],
                "pga_v": float(np.max(np.abs(prepared.ground.vertical))) / 0.01,
                "pga_h": float(np.max(np.abs(prepared.ground.horizontal))) / 0.01,
                "time_shift": case.ground.time_shift,
                "impact_branches": Counter(b.decode() for b in result.events["impact"] if b),
                "step": result.step, "step_choice": prepared.step_choice,
                "least_impact_loss": float(result.events["energy_loss"][result.events["impact"] != b""].min(
                    initial=math.inf)),
            }
            if gravity is None:
                results[row.name] = (result, case)
    return rows, results


def _check_signals(reached: float, end: float) -> None:
    """The ``progress`` of every run: stop at the next kernel chunk after Ctrl-C or SIGTERM."""
    interrupts.check()


def claim(row: Row, previous: Row | None):
    description = row.paper_description
    if description == "The same as above" and previous is not None:
        description = previous.paper_description
    return CLAIMS.get(description)


def verdict_text(run: dict) -> str:
    if not run["overturned"]:
        return "no"
    side = "+" if run["direction"] > 0 else "-"
    return f"yes, {run['overturn_time']:.2f} s ({side})"


def our_description(m: Motion, run: dict) -> str:
    parts = []
    if m.interaction:
        parts.append("liftoff-slip interaction")
    elif m.liftoff and m.slip:
        parts.append("liftoff and slip (separately)")
    elif m.liftoff:
        parts.append("liftoff, no slip")
    elif m.slip:
        parts.append("slip only")
    else:
        parts.append("rest")
    if m.liftoff:
        parts.append(f"{run['impacts']} impacts" if m.rebound else "no rebound")
    if run["overturned"]:
        parts.append("slips during the fall" if m.fall_slip else "no slip during the fall")
    return ", ".join(parts)


def row_checks(rows: list[Row], gravity: float) -> list[dict]:
    out = []
    previous = None
    for row in rows:
        run = row.runs[gravity]
        c = claim(row, previous)
        verdict_ok = run["overturned"] == row.paper_overturned
        description_ok = True if c is None else bool(c[1](run["motion"]))
        out.append({"row": row, "run": run, "verdict_ok": verdict_ok, "description_ok": description_ok,
                    "claim": None if c is None else c[0]})
        previous = row
    return out


def remarks(rows: list[Row], results: dict, gravity: float, histories: bool) -> list[tuple[str, bool, str]]:
    """The paper's checkable remarks: (remark, holds, what we found). Those about time histories
    need ``results`` (kept for the case files' own gravity only: ``histories``)."""
    by = {r.name: r.runs[gravity] for r in rows}
    out = []
    low = ["fig06a-mu050", "fig07a-mu050", "fig08a-mu050", "fig09a-mu050"]
    out.append(("Bodies on the low-grip foundation (mu = 0.50) only slip",
                all(by[n]["motion"].slip and not by[n]["motion"].liftoff and not by[n]["overturned"] for n in low),
                ", ".join(f"{n[:6]}: max slip {1e3 * by[n]['max_slip']:.0f} mm" for n in low)))
    mexico = ["fig06b-mu052", "fig06b-mu055", "fig07b-mu052", "fig07b-mu055"]
    out.append(("Mexico (long period) overturns at mu = 0.52 and 0.55 at both intensities",
                all(by[n]["overturned"] for n in mexico),
                ", ".join(f"{n}: {verdict_text(by[n])}" for n in mexico)))
    for name, paper_times in (("fig08b-mu052", (33.5, 35.5)), ("fig09b-mu052", (32.5, 33.2, 35.5, 35.9))):
        times = [t for t in by[name]["motion"].interaction_times]
        near = [min((abs(t - p) for t in times), default=math.inf) for p in paper_times]
        out.append((f"Liftoff-slip interaction in {name[3:5].lstrip('0')}({name[5]}) at about "
                    + ", ".join(f"{p:g}" for p in paper_times) + " s (paper's time axis)",
                    bool(times) and max(near) < 0.5,
                    "interaction starts at " + (", ".join(f"{t:.2f}" for t in times) or "none")
                    + " s; nearest to the paper's times within " + ", ".join(f"{d:.2f}" for d in near) + " s"))
    a, b = by["fig10a-mu052"], by["fig09b-mu052"]
    out.append(("Eliminating liftoff (10(a)) changes the slip; the interaction of 9(b) reduces it",
                b["max_slip"] < a["max_slip"] and abs(b["residual_slip"]) < abs(a["residual_slip"]),
                f"max slip 9(b) {1e3 * b['max_slip']:.1f} mm vs 10(a) {1e3 * a['max_slip']:.1f} mm; residual "
                f"{1e3 * b['residual_slip']:.1f} vs {1e3 * a['residual_slip']:.1f} mm"))
    if histories:
        peak = {n: window_peak(results[n][0], 32.0, 33.0) for n in ("fig09b-mu052", "fig10b-mu052", "fig10c-mu052")}
        ratio_c = peak["fig10c-mu052"] / peak["fig09b-mu052"] if peak["fig09b-mu052"] else math.nan
        ratio_b = peak["fig10b-mu052"] / peak["fig09b-mu052"] if peak["fig09b-mu052"] else math.nan
        out.append(("Twice the vertical (10(c)) cuts the liftoff angle about 32.5 s to a tenth; half (10(b)) "
                    "leaves it the same",
                    ratio_c < 0.5 and 0.5 < ratio_b < 2.0,
                    f"peak |rotation| in 32-33 s: 9(b) {peak['fig09b-mu052']:.2e}, 10(b) "
                    f"{peak['fig10b-mu052']:.2e} (x{ratio_b:.2f}), 10(c) {peak['fig10c-mu052']:.2e} "
                    f"(x{ratio_c:.2f}) rad"))
        r10b = results["fig10b-mu052"][0]
        tmax = r10b.summary.max_rotation_time
        out.append(("In 10(b) a large liftoff angle suddenly appears about 33.5 s",
                    abs(tmax - 33.5) < 0.5 or r10b.summary.overturned,
                    f"max rotation {r10b.summary.max_rotation:.3f} rad at {tmax:.2f} s"
                    + (f"; overturns at {r10b.summary.overturn_time:.2f} s" if r10b.summary.overturned else "")))
    return out


def window_peak(result, t0: float, t1: float) -> float:
    t = result.history["time"]
    sel = (t >= t0) & (t <= t1)
    return float(np.max(np.abs(result.history["rotation"][sel]))) if sel.any() else 0.0


CSV_COLUMNS = ("figure", "record", "pga_h", "pga_v", "mu", "gravity", "paper_overturned", "overturned",
               "match", "verdict_match", "description_match", "overturn_time", "direction", "fall_start_time",
               "slip", "liftoff", "interaction", "rebound", "max_rotation", "max_slip", "residual_slip",
               "impacts", "verdict_robust", "paper_description", "case")


def csv_text(rows: list[Row], gravities) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    for gravity in gravities:
        for check in row_checks(rows, gravity):
            row, run, m = check["row"], check["run"], check["run"]["motion"]
            writer.writerow([
                row.figure, row.record, f"{run['pga_h']:.1f}", f"{run['pga_v']:.1f}", f"{row.mu:.2f}",
                gravity, _b(row.paper_overturned), _b(run["overturned"]),
                _b(check["verdict_ok"] and check["description_ok"]), _b(check["verdict_ok"]),
                _b(check["description_ok"]), _num(run["overturn_time"]), run["direction"] or "",
                _num(run["fall_start_time"]), _b(m.slip), _b(m.liftoff), _b(m.interaction), _b(m.rebound),
                f"{run['max_rotation']:.6f}", f"{run['max_slip']:.6f}", f"{run['residual_slip']:.6f}",
                run["impacts"], _b(run["robust"]), row.paper_description, row.name])
    return buffer.getvalue()


def _b(value) -> str:
    return "true" if value else "false"


def _num(value) -> str:
    return "" if value is None else f"{value:.4f}"


def markdown(rows: list[Row], results: dict, gravities, previous: dict | None = None) -> str:
    """``table1.md``: nothing in it depends on when or how fast it was made (the time taken is
    printed instead), so that a rerun changes the committed file only if the results change."""
    lines = ["# Table 1 of the paper, reproduced", "",
             "Generated by `make table1` (`rockslide table1`) from the case files in `configs/table1/` on the "
             "paper's records. The paper's block: 0.2 m high, 0.1 m wide, 10 kg, e = 0.8, nu = 0.95 mu, "
             "dt = 0.1 ms, events located inside the step. Kobe (PEER RSN 1106 N-S and U-D) is scaled to the "
             "horizontal peak keeping the recorded V/H ratio; Mexico (SCT1 N-S and U-D) uses Table 1's vertical "
             "peaks explicitly, because our SCT record's V/H (0.375) differs from the paper's (0.29). Times of "
             "Kobe rows are on the paper's time axis (the PEER record shifted by 25 s).", "",
             "Descriptions are judged on the motion before the rotation first passed alpha for good (model.md, "
             "decision 4): as a block falls the normal force vanishes and its pivot slips whatever mu is, so a "
             "fall with slip can still be 'no slip is observed'. 'Robust' means the verdict holds at dt/2 and "
             "with mu (and nu) 1 % lower and higher; a row that is not robust sits on a knife edge.", ""]
    for gravity in gravities:
        checks = row_checks(rows, gravity)
        n_verdict = sum(c["verdict_ok"] for c in checks)
        n_all = sum(c["verdict_ok"] and c["description_ok"] for c in checks)
        lines += [f"## g = {gravity} m/s^2: {n_verdict}/{len(checks)} verdicts match, "
                  f"{n_all}/{len(checks)} verdicts and descriptions", "",
                  "| figure | record | H peak [gal] | V peak [gal] | mu | paper: overturns | paper: description "
                  "| ours: overturns (time, side) | ours: motion before the fall | max rotation [rad] "
                  "| max / residual slip [mm] | robust | match |",
                  "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
        for c in checks:
            row, run = c["row"], c["run"]
            match = "yes" if c["verdict_ok"] and c["description_ok"] else (
                "**NO (verdict)**" if not c["verdict_ok"] else f"**NO (description: {c['claim']})**")
            robust = "yes" if run["robust"] else "**no: " + ", ".join(
                k for k, v in run["variants"].items() if v["overturned"] != run["overturned"]) + " flips**"
            lines.append(
                f"| {row.figure} | {row.record} | {run['pga_h']:.1f} | {run['pga_v']:.1f} | {row.mu:.2f} "
                f"| {'yes' if row.paper_overturned else 'no'} | {row.paper_description} | {verdict_text(run)} "
                f"| {our_description(run['motion'], run)} | {run['max_rotation']:.4f} "
                f"| {1e3 * run['max_slip']:.1f} / {1e3 * run['residual_slip']:.1f} | {robust} | {match} |")
        lines += ["", f"### The paper's remarks, checked (g = {gravity})", ""]
        for text, holds, found in remarks(rows, results, gravity, histories=gravity == gravities[0]):
            lines.append(f"- {'holds' if holds else '**does not hold**'}: {text}. Found: {found}.")
        lines.append("")
    lines += impact_law_comparison(rows, gravities, previous or {})
    lines += findings(rows, gravities)
    lines += [""]
    return "\n".join(lines)


#: The rows with liftoff-slip impacts, compared with rockslide 0.1's impact rule ("slip velocity
#: unchanged"), whose figures `IMPACT_LAW_V01` (in the configs folder) keeps.
IMPACT_LAW_ROWS = ("fig08b-mu052", "fig09b-mu052", "fig10b-mu052", "fig10c-mu052")
IMPACT_LAW_V01 = "impact-law-v0.1.csv"


def previous_figures(configs: Path) -> dict:
    """rockslide 0.1's figures of `IMPACT_LAW_ROWS`: ``{(case, gravity): row}`` ({} if absent)."""
    path = configs / IMPACT_LAW_V01
    if not path.is_file():
        return {}
    with path.open(newline="") as handle:
        return {(r["case"], float(r["gravity"])): r for r in csv.DictReader(handle)}


def impact_law_comparison(rows: list[Row], gravities, previous: dict) -> list[str]:
    """The liftoff-slip rows under rockslide 0.1's impact rule and under the revised law
    (model.md decision 2), side by side."""
    if not previous:
        return []
    out = ["## The revised impact law: the liftoff-slip rows, rockslide 0.1 -> now", "",
           "rockslide 0.1 kept the slip velocity at an impact and multiplied the rotation rate by e, which "
           "could create kinetic energy when the block slid toward the landing edge. The revised law (model.md "
           "decision 2: stick, slip or flat landing, the landing edge's friction bounded by Coulomb's law) never "
           "does: the least energy any impact of the table took is "
           + ", ".join(f"{min(r.runs[g]['least_impact_loss'] for r in rows):.3g} J (g = {g})" for g in gravities)
           + ". Impacts are counted with their branch (stick / slip / flat). The end of liftoff (decision 3, "
           "revised) also moves the impact counts of rows without slip by one (8(c), 9(c)).", "",
           "| figure | g [m/s^2] | overturns | impacts | max rotation [rad] | max slip [mm] | residual slip [mm] "
           "| liftoff-slip interaction starts [s] |",
           "|---|---|---|---|---|---|---|---|"]
    by_name = {row.name: row for row in rows}
    for name in IMPACT_LAW_ROWS:
        row = by_name[name]
        for gravity in gravities:
            old, run = previous.get((name, float(gravity))), row.runs[gravity]
            if old is None:
                continue
            branches = run["impact_branches"]
            now_impacts = f"{run['impacts']} ({'/'.join(str(branches[b]) for b in ('stick', 'slip', 'flat'))})"
            old_times = old["interaction_times"].replace(" ", ", ")
            new_times = ", ".join(f"{t:.2f}" for t in run["motion"].interaction_times)
            out.append(
                f"| {row.figure} | {gravity} | {'yes' if old['overturned'] == 'true' else 'no'} -> "
                f"{'yes' if run['overturned'] else 'no'} | {old['impacts']} -> {now_impacts} "
                f"| {float(old['max_rotation']):.4f} -> {run['max_rotation']:.4f} "
                f"| {1e3 * float(old['max_slip']):.1f} -> {1e3 * run['max_slip']:.1f} "
                f"| {1e3 * float(old['residual_slip']):.1f} -> {1e3 * run['residual_slip']:.1f} "
                f"| {_rounded_times(old_times)} -> {new_times} |")
    return out + [""]


def _rounded_times(text: str) -> str:
    return ", ".join(f"{float(t):.2f}" for t in text.split(", ") if t)


def findings(rows: list[Row], gravities) -> list[str]:
    out = ["## Findings", ""]
    for gravity in gravities:
        for c in row_checks(rows, gravity):
            row, run = c["row"], c["run"]
            if c["verdict_ok"] and c["description_ok"]:
                continue
            other = [g for g in gravities if g != gravity]
            other_ok = [row.runs[g]["overturned"] == row.paper_overturned for g in other]
            why = []
            if not run["robust"]:
                why.append("the verdict is not robust (it flips under " + ", ".join(
                    k for k, v in run["variants"].items() if v["overturned"] != run["overturned"]) + ")")
            if other_ok and all(other_ok):
                why.append(f"with g = {other[0]} the verdict matches the paper")
            if run["max_rotation"] > 0.5 * (math.pi / 2) and not run["overturned"]:
                why.append("the block rocks far (max rotation above pi/4) without overturning")
            out.append(f"- {row.figure} mu = {row.mu:.2f} at g = {gravity}: "
                       + ("verdict" if not c["verdict_ok"] else f"description ({c['claim']})")
                       + " differs from the paper; " + ("; ".join(why) if why else "cause not identified") + ".")
    knife = [f"{r.figure} mu = {r.mu:.2f} (g = {g})" for r in rows for g in gravities if not r.runs[g]["robust"]]
    out.append("- Knife-edge rows (verdict flips with dt/2 or mu +- 1 %): " + (", ".join(knife) or "none") + ".")
    if len(out) == 3 and not knife:
        out.insert(2, "- Every verdict and description matches the paper.")
    return out


FIGURES = {
    "fig06": ("Mexico 1985, 600 gal", [("(a)", "fig06a-mu050"), ("(b)", "fig06b-mu052")]),
    "fig07": ("Mexico 1985, 800 gal", [("(a)", "fig07a-mu050"), ("(b)", "fig07b-mu052")]),
    "fig08": ("Kobe 1995 (Hyogoken-nanbu), 600 gal", [("(a)", "fig08a-mu050"), ("(b)", "fig08b-mu052"),
                                                        ("(c)", "fig08c-mu055")]),
    "fig09": ("Kobe 1995 (Hyogoken-nanbu), 800 gal", [("(a)", "fig09a-mu050"), ("(b)", "fig09b-mu052"),
                                                        ("(c)", "fig09c-mu055")]),
    "fig10": ("Kobe 1995, 800 gal, mu = 0.52", [("(a) no liftoff (on its side)", "fig10a-mu052"),
                                                ("(b) half vertical", "fig10b-mu052"),
                                                ("(c) twice vertical", "fig10c-mu052")]),
}


def write_figures(results: dict, out: Path, overwrite: bool = True, staging=None) -> list[Path]:
    paths = []
    for stem, (title, panels) in FIGURES.items():
        entries = []
        for label, name in panels:
            result, case = results[name]
            entries.append((label, result, f"mu = {case.contact.mu_static:.2f}: {result.summary.verdict}"))
        fig = plots.paper_figure(entries, title=f"Figure {int(stem[3:])}: {title}")
        paths.append(plots.save_figure(fig, out / f"{stem}.png", overwrite=overwrite, staging=staging))
    paths.append(plots.save_figure(criteria_map_figure(), out / "fig05.png", overwrite=overwrite,
                                   staging=staging))
    return paths


def criteria_map_figure(height: float = 0.2, width: float = 0.1, gravity: float = 9.80665):
    """The paper's Figure 5: modes initiated from rest over |A_h| and mu for A_v = -0.5, 0, +0.5 g."""
    ah = np.linspace(0.0, 1.5, 301)
    mu = np.linspace(0.0, 1.2, 241)
    maps = [(f"A_v = {av:+.1f} g", criteria.mode_map(ah, mu, av, width / 2, height / 2, gravity),
             criteria.mode_boundaries(ah, av, width / 2, height / 2, gravity)) for av in (-0.5, 0.0, 0.5)]
    return plots.criteria_figure(ah, mu, maps, title=f"Figure 5: modes initiated from rest, B/H = "
                                                     f"{width / height:g} (eqs. 6, 11, 26)")


def reproduce(configs: Path, records_dir: Path, out: Path) -> dict:
    """Run the table, write ``table1.md``, ``table1.csv`` and the figures into ``out``, all
    published together (`files.Staging`): after Ctrl-C or an error, ``out`` holds what it held
    before, not new figures beside an old table."""
    started = time.perf_counter()
    rows, results = run_table(configs, records_dir)
    gravities = list(rows[0].runs)
    for name in ("table1.csv", "table1.md"):
        check_destination(out / name, overwrite=True)          # the folder made, or a clear error
    with Staging(overwrite=True) as staging:
        figures = write_figures(results, out, staging=staging)
        for name, text in (("table1.csv", csv_text(rows, gravities)),
                           ("table1.md", markdown(rows, results, gravities, previous_figures(configs)))):
            with atomic_write(out / name, overwrite=True, what="table", staging=staging) as handle:
                handle.write(text.encode())
        staging.publish()
    elapsed = time.perf_counter() - started
    summary = {}
    for gravity in gravities:
        checks = row_checks(rows, gravity)
        summary[gravity] = {"verdicts": sum(c["verdict_ok"] for c in checks),
                            "all": sum(c["verdict_ok"] and c["description_ok"] for c in checks),
                            "rows": len(checks)}
    return {"elapsed": elapsed, "summary": summary, "figures": figures,
            "files": [out / "table1.md", out / "table1.csv"], "rows": rows, "results": results}


__all__ = ["PAPER_TABLE", "reproduce", "run_table", "motion", "criteria_map_figure"]
