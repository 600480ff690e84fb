"""What the commands print, as text: a run's summary, a record's description, a stored file's
summary. The Python API gives the same texts (`RunResult` and the study results carry them)."""

from __future__ import annotations

import math


def run_text(name: str, summary, neighbourhood: dict | None = None, *, ground=None, units=None) -> str:
    """The printout of a run (`human_summary`); with its ensemble's summary (`ensemble.summarise`),
    led by the probability of overturning when a neighbour flips the verdict (`ensemble.describe`)."""
    lines = human_summary(name, summary, ground=ground, units=units).split("\n")
    if neighbourhood is not None:
        from ..analyses import ensemble as ens
        described = ens.describe(neighbourhood, lines[0].split(": ", 1)[1])
        lines = [f"{name}: {described[0]}", *lines[1:], *described[1:]]
    return "\n".join(lines)


def human_summary(name, summary, *, ground=None, units=None) -> str:
    """A short text summary of one run.

    Parameters
    ----------
    name : str
    summary : Summary
    ground : dict, optional
        The ground motion as applied (`records.GroundMotion.as_applied`).
    units : dict, optional
        The case's units as written (`case.Case.units`): peaks are shown in the unit of
        ``ground.scale.pga_horizontal`` (the vertical: of ``pga_vertical`` if given), else in gal,
        and in g.
    """
    from ..units import percent_text

    units = units or {}
    verdict = summary.verdict
    if (summary.status == "ok" and not summary.overturned and not summary.undecided
            and math.isfinite(summary.max_rotation_ratio)):
        verdict += f", {percent_text(summary.max_rotation_ratio)} of alpha"
    lines = [f"{name}: {verdict}"]
    if ground is not None:
        lines.append("  " + _ground_line(ground, units))
        if ground.get("components"):
            lines.append("  " + _components_line(ground["components"], units))
    if summary.overturned:
        direction = "+" if summary.direction > 0 else "-"
        fall = ("" if summary.fall_start_time is None
                else f", falling since {summary.fall_start_time:.4f} s (rotation past alpha)")
        lines.append(f"  overturned at {summary.overturn_time:.4f} s, rotation {direction}pi/2{fall}")
    alpha = (f" (alpha {summary.alpha:.4f} rad, {math.degrees(summary.alpha):.2f} deg)"
             if math.isfinite(summary.alpha) else "")
    lines.append(f"  max rotation {summary.max_rotation:.5f} rad "
                 f"({math.degrees(summary.max_rotation):.3f} deg)"
                 f" at {summary.max_rotation_time:.3f} s{alpha}; impacts {summary.impacts}")
    lines.append(f"  max slip {1000 * summary.max_slip:.2f} mm; "
                 f"residual slip {1000 * summary.residual_slip:.2f} mm")
    seen = ", ".join(f"{s} {summary.time_in_state.get(s, 0.0):.2f} s" if s != "OVERTURNED" else s
                     for s in summary.states_seen)
    lines.append(f"  states: {seen}")
    return "\n".join(lines)


def _components_line(components: dict, units: dict) -> str:
    """``two components (0 deg, 90 deg), block at 30 deg: along 674 gal, across 800 gal (59 % of the
    motion ignored by the planar model)``."""
    from ..units import acceleration_text

    unit = units.get("ground.scale.pga_horizontal")
    azimuths = ", ".join(f"{math.degrees(components[k]):g}" for k in ("azimuth_1", "azimuth_2"))
    return (f"two components (azimuths {azimuths} deg), block at {math.degrees(components['orientation']):g} deg: "
            f"peak along {acceleration_text(components['pga_along'], unit)}, across "
            f"{acceleration_text(components['pga_across'], unit)} (ignored by the planar model: "
            f"{100 * components['ignored_share']:.0f} % of the horizontal Arias intensity)")


def _ground_line(ground: dict, units: dict) -> str:
    """``ground as applied: peaks 700 gal (0.714 g) H, 350 gal (0.357 g) V (records x1.19)``."""
    from ..units import acceleration_text

    h_unit = units.get("ground.scale.pga_horizontal")
    v_unit = units.get("ground.scale.pga_vertical", h_unit)
    scales = [(role, ground[f"scale_{role}"]) for role in ("horizontal", "vertical")
              if ground.get(f"scale_{role}") is not None]
    peaks = (f"peaks {acceleration_text(ground['pga_horizontal'], h_unit)} H, "
             f"{acceleration_text(ground['pga_vertical'], v_unit)} V")
    if not scales:
        if ground["pga_horizontal"] == 0.0 and ground["pga_vertical"] == 0.0:
            return "ground as applied: still (no record: a free vibration)"
        return f"ground as applied: {peaks} (analytic pulses, not scaled)"
    if len(scales) == 2 and f"{scales[0][1]:.4g}" == f"{scales[1][1]:.4g}":
        factors = f"x{scales[0][1]:.4g}"
    else:
        factors = ", ".join(f"x{factor:.4g} {role[0].upper()}" for role, factor in scales)
    return f"ground as applied: {peaks} (records {factors})"


def run_lines(result, *, units=None) -> list[str]:
    """The printout of `run` (`rockslide run`): its summary, ensemble and floor (without the files)."""
    lines = run_text(result.name, result.summary, result.ensemble, ground=result.ground or None,
                     units=units).split("\n")
    if result.planes is not None:
        lines += planes_lines(result.planes)
    if (result.integration or {}).get("mode") == "auto":
        lines.append(f"  solver.dt: {result.integration['note']}")
    if result.floor is not None:
        from ..engine.prepare import floor_peaks_text
        if "description" in result.floor:
            lines.append(f"  {result.floor['description']}")
        lines.append(f"  {floor_peaks_text({k: v for k, v in result.floor.items() if k != 'description'})}")
    return lines


def run_payload(result) -> dict:
    """The JSON object of `run` (``rockslide run --json``), without its files and time."""
    from ..io import results

    floor = result.floor
    return {"name": result.name, **results.summary_to_json_dict(result.summary, result.events),
            "ground": result.ground, "floor": floor, "ensemble": results.json_ready(result.ensemble),
            "integration": results.json_ready(result.integration), "planes": results.json_ready(result.planes)}


def record_lines(record, details: dict) -> list[str]:
    """``rockslide info RECORD``'s printout of `io.records.record_info`'s ``details``."""
    lines = [f"{record}",
             f"  format    {details['format']}",
             f"  units     {details['units']} (converted to m/s^2)",
             f"  samples   {details['npts']}, dt = {details['dt']:g} s, "
             f"duration {details['duration']:g} s, starts at {details['start']:g} s",
             f"  peak      {details['peak_gal']:.2f} gal = {details['peak_g']:.4f} g "
             f"({'+' if details['peak_signed'] > 0 else '-'}) at t = {details['peak_time']:g} s",
             f"  mean      {details['mean'] / 0.01:.3f} gal"]
    if details.get("azimuth") is not None:
        lines.append(f"  azimuth   {math.degrees(details['azimuth']):g} deg (from the title line; "
                     "ground.horizontal_1/2)")
    for key, value in (details.get("cosmos") or {}).items():
        if value not in (None, "") and key != "comments":
            lines.append(f"  {key.replace('_', ' '):<9} {value}")
    lines.append(f"  sha256    {details['sha256']}")
    return lines


def stored_lines(path, details: dict) -> list[str]:
    """``rockslide info FILE``'s printout of what a file rockslide wrote holds (`describe_file`)."""
    if details["kind"] == "result":
        from .stored import read_result
        run = read_result(path)
        text = "\n".join(run_lines(run))
        return [f"{text}\n  (read from {path}; rockslide {run.attrs.get('rockslide_version', '?')})"]
    lines = [f"{path}", *(f"  {k:<18}{v}" for k, v in details.items() if not isinstance(v, (dict, list)))]
    lines += [f"  {state}: median {fit['median']}, beta {fit['beta']}"
              for state, fit in details.get("fits", {}).items()]
    lines += [f"  {curve}: " + ", ".join(f"{key} {value:.4g}" for key, value in numbers.items() if value is not None)
              for curve, numbers in details.get("rates", {}).items()]
    return lines


def json_ready(value):
    """``value`` with numpy numbers and arrays as plain numbers and lists, NaN as None
    (`io.results.json_ready`): what a JSON printout holds."""
    from ..io.results import json_ready as ready

    return ready(value)


def planes_lines(planes: dict) -> list[str]:
    """A box's or a mesh's screening in both planes: each plane's verdict and the worse (`api.runs._planes`)."""
    lines = [f"  both planes ({planes['screening']}):"]
    for name in ("width", "depth"):
        plane = planes[name]
        where = "" if plane["orientation"] is None else f" at {math.degrees(plane['orientation']) % 360:g} deg"
        ratio = plane["max_rotation_ratio"]
        how = plane.get("note") or ("" if plane["overturned"] else f", {100 * ratio:.3g} % of alpha")
        lines.append(f"    {name} plane{where}: {plane['verdict']}{how if plane.get('note') is None else '; ' + how}")
        if plane.get("body"):
            lines.append(f"      {plane['body']}")
    worse = planes[planes["worse"]]
    lines.append(f"    verdict of the body: {worse['verdict']} (the {planes['worse']} plane)")
    return lines
