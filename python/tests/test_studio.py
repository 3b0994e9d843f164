"""fivebar.Studio: the studio's state without a page (docs/python.md "Studio"), checked against the
CLI's JSON of the saved file."""
import shutil

import pytest

import fivebar
from conftest import SHOWCASE, run_cli

LINK = "stations.index.mechanisms.lower.links[2]"
BASE = "stations.index.mechanisms.lower.bases[1][0]"


@pytest.fixture
def design(tmp_path):
    path = tmp_path / "iros2022.yaml"
    shutil.copy(SHOWCASE, path)
    return path


def margins(coverage):
    out = {m["mechanism"]: m["margin_mm"] for m in coverage["mechanisms"]}
    out["shared"] = coverage["shared"]["margin_mm"]
    return out


def test_the_live_figures_are_fivebar_coverage_of_the_saved_file(design):
    s = fivebar.Studio(str(design))
    s.set(LINK, 15.75)
    s.set(BASE, 13.0)
    assert s.edits == {LINK: 15.75, BASE: 13.0}
    fig = s.figures("index")
    preview = s.preview()
    saved = s.save()
    assert saved["saved"] and saved["changes"] == preview["changes"]
    assert s.edits == {}
    cli = run_cli("coverage", design, "--station", "index", "--json")["stations"][0]
    assert margins(fig["coverage"]) == margins(cli)
    # Not the unedited design's margins: the edit took effect.
    before = run_cli("coverage", SHOWCASE, "--station", "index", "--json")["stations"][0]
    assert margins(before) != margins(cli)


def test_a_save_changes_only_the_edited_lines_and_keeps_every_comment(design):
    original = design.read_text().split("\n")
    s = fivebar.Studio(str(design))
    s.set(LINK, 15.5)
    diff = s.save()["changes"]
    saved = design.read_text().split("\n")
    assert len(saved) == len(original)
    changed = [i + 1 for i, (a, b) in enumerate(zip(original, saved)) if a != b]
    assert changed == [c["line"] for c in diff] and len(changed) == 1
    assert all(c["before"] == original[c["line"] - 1] and c["after"] == saved[c["line"] - 1] for c in diff)
    for a, b in zip(original, saved):
        if "#" in a:
            assert a[a.index("#"):] == b[b.index("#"):]


def test_a_refused_edit_names_the_file_line_and_key_and_writes_nothing(design):
    text = design.read_text()
    s = fivebar.Studio(str(design))
    s.set("stations.index.mechanisms.lower.links[0]", -1)
    with pytest.raises(fivebar.InputError, match=r"iros2022\.yaml:[0-9]+: .*links\[0\]"):
        s.figures("index")
    with pytest.raises(fivebar.InputError):
        s.save()
    assert design.read_text() == text


def test_a_file_changed_on_disk_is_not_overwritten(design):
    s = fivebar.Studio(str(design))
    s.set(LINK, 15.5)
    changed = design.read_text() + "\n# edited elsewhere\n"
    design.write_text(changed)
    r = s.save()
    assert r["saved"] is False and "changed on disk" in r["reason"]
    assert design.read_text() == changed
    s.reload()
    assert s.text == changed and s.edits == {}


def test_the_pattern_is_fivebar_patterns_of_the_edited_file(design, tmp_path):
    s = fivebar.Studio(str(design))
    s.set("patterns.stretch.separation_mm", 3.0)
    played = s.pattern("stretch", "index")
    edited = tmp_path / "edited.yaml"
    edited.write_text(s.edited_text)
    cli = run_cli("pattern", edited, "--station", "index", "--pattern", "stretch", "--json", "--samples",
                  "--out", tmp_path / "out")
    assert played["samples"] == cli["samples"] and played["passed"] == cli["passed"]
    assert cli["worst"]["moved_samples"] > 0  # the priority rule at work
    assert len(played["frames"]) == len(played["samples"])
