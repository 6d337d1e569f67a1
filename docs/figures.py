"""The site's figures: made by quadcog's own commands, copied into docs/figures/ and committed.

``python docs/figures.py`` (or ``make docs-figures``) runs the commands below into a temporary
folder (about two minutes on two cores: the failure map is most of it) and copies each figure
to ``docs/figures/NAME.png``. The pages show a figure where they hold ``<!-- figure NAME -->``:
the docs hook (``docs/gen_reference.py``) puts the image there with its caption from
``FIGURES``, so a caption is written once. ``tests/test_docsite.py`` fails when a page names a
figure file (``flight.png``, ``failure_map.png``, ...) that it does not show, and when a figure
of this table is missing from docs/figures/ or from the pages it lists.

The figures are committed rather than drawn at every build: the build stays fast and needs no
compiler, and a figure changes only when this command is run again (its run is named in
docs/figures/README.md).
"""
from dataclasses import dataclass
from pathlib import Path
import shutil
import subprocess
import sys
import tempfile

ROOT = Path(__file__).resolve().parent.parent
FOLDER = ROOT / "docs" / "figures"
CRAZYPAD = "tests/data/crazypad/controller_data"
RAMPS = ROOT / "docs" / "howto" / "sweep.md"      # the sweep file of the how-to, run as written

__all__ = ["Figure", "FIGURES", "RUNS", "FOLDER", "make"]


@dataclass(frozen=True)
class Figure:
    """One figure of the site.

    Parameters
    ----------
    name : str
        ``docs/figures/<name>.png``, and the marker ``<!-- figure <name> -->``.
    run : str
        The key of ``RUNS`` whose command draws it.
    source : str
        The file the command writes, relative to the run's output folder.
    caption : str
        What to see in it (Markdown).
    pages : tuple of str
        The pages (under docs/) that show it.
    """

    name: str
    run: str
    source: str
    caption: str
    pages: tuple[str, ...]

    @property
    def shows(self) -> str:
        """str: The file name quadcog gives the figure (``flight.png``), as pages name it."""
        return Path(self.source).name


# name: the quadcog command line (its output folder is appended as --out DIR)
RUNS = {
    "paper": ["paper"],
    "analysis": ["analyze"],
    "parcel": ["run", "parcel-hover", "--quiet"],
    "identify": ["identify", f"{CRAZYPAD}/add_weight_W1_near_M3/E9_log00",
                 f"{CRAZYPAD}/add_weight_W1_near_M3/E9_log01",
                 f"{CRAZYPAD}/add_weight_W1_near_M3/E9_log02",
                 "--baseline", f"{CRAZYPAD}/normal_flight/E9_log00",
                 f"{CRAZYPAD}/normal_flight/E9_log01"],
    "ramps": ["sweep", "RAMPS"],
}

_PAPER = {
    "fig3a": "Fig. 3(a), cascade PD on the balanced vehicle: the position follows the "
             "reference (dashed) to a centimetre after the start.",
    "fig3b": "Fig. 3(b), feedback linearization on the balanced vehicle: the error panel stays "
             "below a millimetre once the initial offset is gone.",
    "fig4": "Fig. 4, cascade PD after the CoG steps 6 cm forward and 6 cm left at 1 s: the "
            "attitude holds a standing error and the position settles 1.3 m away (the CoG "
            "panel shows the step).",
    "fig5": "Fig. 5, feedback linearization after the same step: the dashed commanded thrust "
            "of one rotor goes negative 74 ms after the step, the rotor gives zero and the "
            "vehicle tips over at 1.35 s.",
    "fig6": "Fig. 6, adaptive feedback linearization after the step: a transient of up to "
            "1.6 m while the estimate r_hat (CoG panel) moves to the true offset, then a "
            "settled error of about 4 cm.",
    "fig7": "Fig. 7, adaptive FL while the CoG moves slowly: the estimate follows the ramp and "
            "the vehicle tracks within a centimetre once it has caught up.",
    "fig8": "Fig. 8, adaptive FL with force and moment pulses while the CoG moves: each pulse "
            "shows as a spike in the error panel, which decays again.",
}

FIGURES: tuple[Figure, ...] = tuple(
    Figure(f"paper-{key}", "paper", f"{key}/flight.png", text, ("tour/paper.md",))
    for key, text in _PAPER.items()) + (
    Figure("paper-cog-step", "paper", "cog_step_comparison.png",
           "The three laws of the paper through the same CoG step at hover: cascade PD drifts "
           "to a standing error, feedback linearization diverges, the adaptive law recovers.",
           ("tour/paper.md", "index.md")),
    Figure("beyond", "paper", "beyond/beyond.png",
           "The laws beyond the paper under real sensors and motors: which of them catch the "
           "CoG jump, and how fast their estimates settle.", ("tour/beyond.md",)),
    Figure("flight", "paper", "fig5/flight.png",
           "A flight figure (`quadcog run fig5`): position and reference, attitude, position "
           "error, CoG and its estimate, rotor thrusts with the commanded ones dashed, and "
           "the moments.",
           ("getting-started.md", "tour/simulate.md", "tour/scenarios.md",
            "howto/controller.md", "px4.md")),
    Figure("pd-sigma", "analysis", "pd_sigma.png",
           "Singular values of cascade PD's loop transfer matrix at hover: the crossover "
           "frequencies of the four loops, no peak that would signal a small margin.",
           ("tour/analysis.md",)),
    Figure("zero-dynamics", "analysis", "zero_dynamics.png",
           "The zero dynamics' eigenvalues over admissible CoG offsets: they do not move with "
           "r_G (0, 0, -c_x/m, -c_y/m).", ("tour/analysis.md",)),
    Figure("lyapunov", "analysis", "lyapunov.png",
           "The adaptive law's Lyapunov function V along Fig. 6: it rises after the step, "
           "which the paper's proof does not allow; with the position loop removed and the "
           "true B (an oracle) it barely rises.", ("tour/analysis.md", "model.md")),
    Figure("failure-map", "analysis", "failure_map.png",
           "Tail RMS after a CoG step at hover over a 41 x 41 grid of (x_G, y_G), one panel "
           "per law: grey outside the admissible disc, dark where the flight diverged.",
           ("tour/analysis.md", "tour/sweeps.md")),
    Figure("identify", "identify", "identify.png",
           "Three CrazyPAD flights of a Crazyflie with a weight near motor 3 against two normal "
           "flights: left, each 1 s block's estimate of the CoG shift (mm) with the pooled "
           "estimate and its 95 % band (x_G swings with the direction of flight, the speed "
           "effect of sec. 1); right, the rotors' moments about O against the weight's moment "
           "m g [y_G, -x_G] of the estimate.",
           ("identify.md",)),
    Figure("parcel-hover", "parcel", "flight.png",
           "`quadcog run parcel-hover`: payload-adaptive FL with real sensors and motors picks "
           "up a parcel of +30 % mass, 3 cm off axis, at 2 s and drops it at 12 s. The CoG "
           "panel: the x_G estimate reaches the whole body's CoG (dashed) within about half a "
           "second, the mass (dotted, right axis) steps with it; z_G, which hardly shows in a "
           "hover, is not learnt. Each change costs about 15 cm of position error.",
           ("howto/payload.md",)),
    Figure("ramps-failure-map", "ramps", "failure_map.png",
           "The sweep of the how-to: its failure map, drawn because two components of one CoG "
           "offset vary (here only two offsets, so two cells per controller).",
           ("howto/sweep.md",)),
    Figure("ramps-survival", "ramps", "survival_cog_0_ramp.png",
           "The sweep of the how-to (12 flights): the share of flights that survive per "
           "controller against the ramp length of the CoG change.",
           ("howto/sweep.md", "tour/sweeps.md")),
    Figure("ramps-tail-rms", "ramps", "tail_rms_hist.png",
           "The same sweep: a histogram of the tail RMS per controller; diverged flights "
           "are counted at the right edge.", ("howto/sweep.md", "tour/sweeps.md")),
)


def _ramps_file(folder: Path) -> Path:
    """The how-to's sweep file, cut out of its page (so the figure is of what the page runs)."""
    text = RAMPS.read_text()
    body = text.split("cat > ramps.toml <<'TOML'\n", 1)[1].split("\nTOML\n", 1)[0]
    path = folder / "ramps.toml"
    path.write_text(body + "\n")
    return path


def make(out: Path = FOLDER) -> list[Path]:
    """Run every command of ``RUNS`` and copy the figures of ``FIGURES`` into ``out``.

    Parameters
    ----------
    out : pathlib.Path
        Where the PNG files go (default docs/figures/).

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    out.mkdir(parents=True, exist_ok=True)
    written = []
    with tempfile.TemporaryDirectory(prefix="quadcog-figures-") as tmp:
        base = Path(tmp)
        for run, args in RUNS.items():
            args = [str(_ramps_file(base)) if a == "RAMPS" else a for a in args]
            command = [sys.executable, "-m", "quadcog", *args, "--out", str(base / run)]
            print("$ quadcog", " ".join(args), "--out", f"<tmp>/{run}", flush=True)
            subprocess.run(command, cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
        for fig in FIGURES:
            target = out / f"{fig.name}.png"
            shutil.copyfile(base / fig.run / fig.source, target)
            written.append(target)
    return written


if __name__ == "__main__":
    for path in make(Path(sys.argv[1]) if len(sys.argv) > 1 else FOLDER):
        print("wrote", path.relative_to(ROOT) if path.is_relative_to(ROOT) else path)
