"""`quadcog paper`: the paper's figures as scenarios, each claim as numbers and a verdict."""
from dataclasses import dataclass
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from quadcog import config
from quadcog.scenarios.lookup import scenario_path
from quadcog.scenarios.scenario import load_scenario, run_with_progress, write_outputs

__all__ = ["TRACKS", "FAILS", "RECOVERS", "ESTIMATE", "ESTIMATE_FLOOR", "CSV_EVERY", "Claim",
           "CLAIMS", "verdict", "readme_table", "PAPER_FILES", "run_paper"]

TRACKS = 0.05        # m: tail RMS under which a balanced run "tracks" (Fig. 3)
FAILS = 0.50         # m: tail RMS over which (or diverged) a controller "fails" (Figs. 4, 5)
RECOVERS = 0.10      # m: tail RMS under which the adaptive controller "recovers" (Figs. 6-8)
ESTIMATE = 0.10      # relative error allowed on the x_G, y_G estimates ...
ESTIMATE_FLOOR = 0.003   # ... or this many metres, for components that are (near) zero
CSV_EVERY = 10           # the paper run's trajectory.csv keeps every 10th step


@dataclass(frozen=True)
class Claim:
    """One claim of the paper, checked on one shipped scenario.

    Parameters
    ----------
    figure : str
        The paper's figure ("Fig. 6").
    scenario : str
        The shipped scenario that reproduces it.
    text : str
        The claim in words.
    kind : str
        "tracks", "fails" or "recovers": how ``verdict`` judges it.
    """
    figure: str
    scenario: str
    text: str
    kind: str            # "tracks" | "fails" | "recovers"


CLAIMS = (
    Claim("Fig. 3(a)", "fig3a", "Cascade PD tracks a trajectory when the quadrotor is balanced",
          "tracks"),
    Claim("Fig. 3(b)", "fig3b", "Feedback linearization tracks when the quadrotor is balanced",
          "tracks"),
    Claim("Fig. 4", "fig4", "Cascade PD fails to stabilize the quadrotor when the CoG moves",
          "fails"),
    Claim("Fig. 5", "fig5", "Feedback linearization fails to stabilize the quadrotor when the "
          "CoG moves", "fails"),
    Claim("Fig. 6", "fig6", "Adaptive FL stabilizes the quadrotor after a CoG change", "recovers"),
    Claim("Fig. 7", "fig7", "Adaptive FL tracks while the CoG changes dynamically", "recovers"),
    Claim("Fig. 8", "fig8", "Adaptive FL is robust to disturbance forces and moments while the "
          "CoG changes", "recovers"),
)


def _estimate_ok(m):
    if m.get("r_hat_final") is None:
        return None
    r_hat, r = np.array(m["r_hat_final"][:2]), np.array(m["r_G_final"][:2])
    return bool(np.all(np.abs(r_hat - r) <= np.maximum(ESTIMATE * np.abs(r), ESTIMATE_FLOOR)))


def verdict(claim: Claim, m: dict[str, Any]) -> tuple[str, str]:
    """Whether one claim holds in its run.

    Parameters
    ----------
    claim : Claim
        The claim.
    m : dict
        Its run's metrics (metrics.json: errors in m, times in s).

    Returns
    -------
    tuple of (str, str)
        (holds: 'yes' | 'partly' | 'no', a note with the numbers).
    """
    tail, peak = m["rms_position_error_tail"], m["max_position_error"]
    if claim.kind == "tracks":
        if not m["diverged"] and tail < TRACKS:
            return "yes", f"tail RMS {100 * tail:.2f} cm < {100 * TRACKS:.0f} cm"
        return "no", f"tail RMS {100 * tail:.2f} cm (diverged: {m['diverged']})"
    if claim.kind == "fails":
        if m["diverged"]:
            return "yes", f"diverged at {m['diverged_at']:.2f} s ({m['diverged_reason']})"
        if tail > FAILS:
            return "partly", (f"not a crash: the vehicle stays up with a standing position "
                              f"error of {tail:.2f} m (tail RMS > {FAILS:.1f} m); the paper "
                              f"shows a failure to stabilize")
        return "no", f"tail RMS {100 * tail:.1f} cm: it copes"
    est = _estimate_ok(m)
    ok = not m["diverged"] and tail < RECOVERS and est
    note = (f"tail RMS {100 * tail:.2f} cm, peak error {100 * peak:.0f} cm during the change; "
            f"x_G, y_G estimates {'within' if est else 'NOT within'} 10 % "
            f"(r_hat = {np.round(np.array(m['r_hat_final']) * 100, 2).tolist()} cm, "
            f"true {np.round(np.array(m['r_G_final']) * 100, 2).tolist()} cm)")
    if ok and peak > FAILS:
        return "partly", note + "; the transient is large"
    return ("yes" if ok else "no"), note


def _comparison_plot(results, out):
    import matplotlib
    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 4.2))
    for name, label in (("fig4", "cascade PD (Fig. 4)"), ("fig5", "feedback lin. (Fig. 5)"),
                        ("fig6", "adaptive FL (Fig. 6)")):
        r = results[name]
        e = np.linalg.norm(r.x[:, :3] - r.ref[:, :3], axis=1)
        ax.semilogy(r.t, np.maximum(e, 1e-4), label=label)     # 0 before the step: floored
    ax.axvline(1.0, color="k", ls=":", lw=1)
    ax.text(1.05, 2e-4, "CoG steps to [6, 6, 0] cm", fontsize=8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("position error (m), floored at 0.1 mm")
    ax.set_title("Hover through a CoG step: who survives", pad=24)
    ax.grid(alpha=0.3, which="both")
    ax.legend(loc="lower left", bbox_to_anchor=(0, 1.0), ncol=3, frameon=False,
              borderaxespad=0.2)  # off the data
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def _tex(s):
    return (s.replace("\\", "/").replace("%", r"\%").replace("_", r"\_").replace("#", r"\#")
            .replace("&", r"\&").replace("<", r"$<$").replace(">", r"$>$"))


def _fragment(rows):
    lines = [r"\section{The paper's claims, reproduced}",
             r"Each figure of the paper is a scenario (\texttt{quadcog paper}); thresholds: "
             rf"tracks if the tail RMS error is under {100 * TRACKS:.0f}\,cm; fails if over "
             rf"{100 * FAILS:.0f}\,cm or diverged; recovers if under {100 * RECOVERS:.0f}\,cm "
             r"with the $x_G$, $y_G$ estimates within 10\,\%.", "",
             r"\begin{center}\small", r"\begin{tabular}{p{1.4cm}p{4.4cm}rrp{1.2cm}}",
             r"\toprule figure & claim & tail RMS (m) & max (m) & holds \\ \midrule"]
    for r in rows:
        lines.append(f"{r['figure']} & {_tex(r['claim'])} & {r['rms_position_error_tail']:.3f} & "
                     f"{r['max_position_error']:.3f} & {r['holds']} \\\\")
    lines += [r"\bottomrule", r"\end{tabular}", r"\end{center}", ""]
    for r in rows:
        lines.append(rf"\paragraph{{{r['figure']}}} {_tex(r['note'])}.")
    lines.append(r"\begin{figure}[htbp]\centering"
                 r"\includegraphics[width=0.7\linewidth]{paper/cog_step_comparison.png}"
                 r"\caption{Position error through a CoG step at hover (Figs.~4--6).}\end{figure}")
    for pair in (rows[i:i + 2] for i in range(0, len(rows), 2)):     # two flights per page
        lines.append(r"\begin{figure}[p]\centering")
        for r in pair:
            lines.append(rf"\includegraphics[width=0.82\linewidth]{{paper/{r['scenario']}/flight.png}}"
                         rf"\caption{{{_tex(r['claim'])} (the paper's {r['figure']}).}}"
                         r"\medskip")
        lines.append(r"\end{figure}")
    return "\n".join(lines) + "\n"


def readme_table(rows: list[dict[str, Any]]) -> str:
    """The table of the claims (Markdown), ``readme_table.md``.

    ``python bench/publish.py paper`` copies it into docs/tour/paper.md.

    Parameters
    ----------
    rows : list of dict
        The rows of ``run_paper``.

    Returns
    -------
    str
        The table: tail RMS to 0.1 mm, max to 1 mm.
    """
    lines = ["| figure | claim | tail RMS (m) | max (m) | holds |", "|---|---|---|---|---|"]
    for r in rows:
        tail = (f"diverged at {r['diverged_at']:.2f} s" if r["diverged"]
                else f"{r['rms_position_error_tail']:.4f}")
        lines.append(f"| {r['figure']} | {r['claim']} | {tail} | "
                     f"{r['max_position_error']:.3f} | **{r['holds']}** |")
    return "\n".join(lines)


PAPER_FILES = ("cog_step_comparison.png", "summary.md", "report_fragment.tex",
               "readme_table.md", "summary.json")
"""The files ``run_paper`` writes into its folder besides the scenarios' folders and
``beyond/``, together (``quadcog.files.RunFiles``)."""


def run_paper(out: str | os.PathLike[str], progress: bool = True,
              beyond: bool = True) -> list[dict[str, Any]]:
    """Run the built-in scenarios, draw the figures, write the summaries.

    Parameters
    ----------
    out : str or os.PathLike
        The folder for summary.md, summary.json, report_fragment.tex, readme_table.md and
        the figures (created if needed).
    progress : bool
        Progress bars on stderr.
    beyond : bool
        Also the side-by-side comparison of ``quadcog.studies.beyond`` into ``out/beyond``
        (its section joins the report fragment).

    Returns
    -------
    list of dict
        The summary rows, one per claim: figure, scenario, claim, controller, holds, note
        and the run's metrics (m, s).
    """
    from quadcog.errors import InputError
    from quadcog.files import RUN_FILES, RunFiles, check_outputs, creatable_folder
    from quadcog.studies.beyond import BEYOND_FILES
    out = Path(out)
    # before the minutes of flights: every file the command replaces can be replaced (no
    # folder, link or FIFO in its place) and the folder can be made
    creatable_folder(out, "out", InputError)
    check_outputs([(f"out (its {name})", out / name) for name in PAPER_FILES]
                  + [(f"out (its {c.scenario}/{name})", out / c.scenario / name)
                     for c in CLAIMS for name in RUN_FILES]
                  + ([(f"out (its beyond/{name})", out / "beyond" / name)
                      for name in BEYOND_FILES] if beyond else []))
    rows, results = [], {}
    for claim in CLAIMS:
        scenario = load_scenario(scenario_path(claim.scenario))
        result = run_with_progress(scenario, f"{claim.figure:<9s} {scenario.name}", progress)
        results[claim.scenario] = result
        # every 10th sample (10 ms) in the CSV: the figures are drawn from the full result
        m = write_outputs(result, scenario, out / claim.scenario, every=CSV_EVERY)
        holds, note = verdict(claim, m)
        rows.append(dict(figure=claim.figure, scenario=claim.scenario, claim=claim.text,
                         controller=scenario.controller, holds=holds, note=note,
                         **{k: m[k] for k in ("rms_position_error", "max_position_error",
                                              "final_position_error", "rms_position_error_tail",
                                              "diverged", "diverged_at", "diverged_cause",
                                              "diverged_reason", "r_hat_final", "r_G_final")}))
        print(f"  {claim.figure:<9s} holds: {holds:<6s} {note}")
    md = ["# The paper's claims, reproduced", "",
          f"Thresholds: tracks = tail RMS < {100 * TRACKS:.0f} cm; fails = tail RMS > "
          f"{100 * FAILS:.0f} cm or diverged; recovers = tail RMS < {100 * RECOVERS:.0f} cm with "
          "x_G, y_G estimates within 10 % (or 3 mm for a zero component). Tail = last "
          f"{100 * config.get('metrics.tail_fraction'):g} % of the run.", "",
          "| figure | claim | controller | RMS (m) | max (m) | tail RMS (m) | diverged | holds | "
          "note |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        md.append(f"| {r['figure']} | {r['claim']} | {r['controller']} | "
                  f"{r['rms_position_error']:.3f} | {r['max_position_error']:.3f} | "
                  f"{r['rms_position_error_tail']:.4f} | "
                  f"{'at %.2f s' % r['diverged_at'] if r['diverged'] else 'no'} | "
                  f"**{r['holds']}** | {r['note']} |")
    md += ["", "Figures: `<scenario>/flight.png` for each row, `cog_step_comparison.png`."]
    fragment = _fragment(rows)
    if beyond:
        from quadcog.studies.beyond import run_beyond
        run_beyond(out / "beyond", progress)
        fragment += (out / "beyond" / "beyond_fragment.tex").read_text()
        md += ["", "Beyond the paper: `beyond/beyond.md` (the paper's law, FL with integral "
               "action and the composite law on every CoG scenario, ideal and real)."]
    # the summaries together or not at all (Ctrl-C included), summary.json last
    with RunFiles(out, owned=PAPER_FILES) as files:
        _comparison_plot(results, files.path("cog_step_comparison.png"))
        files.path("summary.md").write_text("\n".join(md) + "\n")
        files.path("report_fragment.tex").write_text(fragment)
        files.path("readme_table.md").write_text(readme_table(rows) + "\n")
        files.path("summary.json").write_text(json.dumps(rows, indent=2) + "\n")
    print(f"wrote {out}/summary.md, summary.json, report_fragment.tex, readme_table.md and the "
          "figures")
    return rows
