"""The report's build copies the paper's and the analysis's results into its folder, and
replaces only copies it made: ``python -m report.pdf --out out`` (the paper's default
``--paper out/paper``) removed the paper's own results, and any folder named paper or analysis
in the folder given to --out was removed with them."""
import os

import pytest

from report.pdf import COPY_MARKER, BuildError, _copy_results


def _results(folder, extra=("metrics.json",)):
    folder.mkdir(parents=True)
    (folder / "report_fragment.tex").write_text("\\section{results}\n")
    (folder / "fig.png").write_bytes(b"png")
    for name in extra:
        (folder / name).write_text("{}")
    return folder


def test_results_given_as_their_own_copy_are_used_in_place(tmp_path):
    paper = _results(tmp_path / "out" / "paper")
    before = sorted(p.name for p in paper.iterdir())
    assert _copy_results(paper, tmp_path / "out" / "paper") is True
    assert sorted(p.name for p in paper.iterdir()) == before


@pytest.mark.parametrize("inner", [True, False])
def test_results_and_copy_that_overlap_are_refused(tmp_path, inner):
    paper = _results(tmp_path / "a" / "paper")
    target = paper / "copy" if inner else tmp_path / "a"
    with pytest.raises(BuildError, match="overlap"):
        _copy_results(paper, target)
    assert (paper / "metrics.json").is_file()


def test_a_folder_that_is_not_a_copy_is_kept(tmp_path):
    paper = _results(tmp_path / "runs" / "paper")
    users = _results(tmp_path / "home" / "paper", extra=("thesis.md",))
    with pytest.raises(BuildError, match="not a copy made by the report"):
        _copy_results(paper, users)
    assert (users / "thesis.md").is_file()
    (users / "thesis.md").unlink()          # a folder of .tex and .png without the marker
    (users / "notes.txt").symlink_to(paper / "metrics.json")
    with pytest.raises(BuildError, match="not a copy made by the report"):
        _copy_results(paper, users)


def test_copies_are_replaced_old_and_new(tmp_path):
    paper = _results(tmp_path / "out" / "paper")
    old = _results(tmp_path / "out" / "report" / "paper", extra=("stale.png",))  # before the marker
    assert _copy_results(paper, old) is True
    assert sorted(p.name for p in old.iterdir()) == sorted(
        [COPY_MARKER, "fig.png", "report_fragment.tex"])
    (paper / "fig.png").unlink()
    assert _copy_results(paper, old) is True            # a marked copy: replaced
    assert not (old / "fig.png").exists()
    assert _copy_results(None, old) is False and not old.exists()


@pytest.mark.parametrize("kind", ["link", "fifo", "folder"])
def test_verify_never_writes_through_what_is_not_a_regular_file(tmp_path, kind, capsys):
    """report.verify wrote its table with write_text: through a link into its target, and
    into a FIFO it blocked; it is refused before the work, with argparse's message."""
    from report.verify import main
    victim = tmp_path / "victim.tex"
    victim.write_text("precious\n")
    out = tmp_path / "verification.tex"
    if kind == "link":
        out.symlink_to(victim)
    elif kind == "fifo":
        os.mkfifo(out)
    else:
        out.mkdir()
    with pytest.raises(SystemExit) as e:
        main(["--out", str(out), "--points", "1"])
    assert e.value.code == 2
    assert "--out" in capsys.readouterr().err
    assert victim.read_text() == "precious\n" and not out.with_suffix(".json").exists()
