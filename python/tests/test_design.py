"""The design from Python: loading, stations and mechanisms as objects, editing numbers by key path,
writing the design back, and errors carrying the file, line and key."""
import pathlib

import pytest

import fivebar
from conftest import SHOWCASE

LINKS = "stations.index.mechanisms.lower.links[2]"


def test_load_gives_the_stations_and_mechanisms_of_the_file(showcase):
    assert showcase.name == "iros2022"
    assert [s.name for s in showcase.stations] == ["index", "thumb"]
    index = showcase.station("index")
    assert [m.name for m in index.mechanisms] == ["lower", "upper"]
    # Table 1 of the paper (docs/design-file.md): index bases (0, 0), (12.5, 0) and (0, 31), (12.5, 31).
    assert index.lower.O1 == (0.0, 0.0) and index.lower.O2 == (12.5, 0.0)
    assert index.upper.O1 == (0.0, 31.0)
    assert index.lower.working_mode == "-+" and index.upper.working_mode == "+-"
    assert index.target.axes == (15.0, 12.0)
    assert "index" in repr(showcase) and "lower" in repr(index)


def test_from_yaml_round_trips_through_to_yaml(showcase):
    text = showcase.to_yaml()
    again = fivebar.Design.from_yaml(text)
    assert again.to_yaml() == text
    assert again.station("thumb").lower.links == showcase.station("thumb").lower.links


def test_with_numbers_edits_by_key_path_and_leaves_the_original(showcase):
    before = showcase.number(LINKS)
    assert before == showcase.station("index").lower.links[2]
    edited = showcase.with_numbers({LINKS: 16.5, "stations.index.target.axes[0]": 14.0})
    assert edited.number(LINKS) == 16.5
    assert edited.station("index").lower.links[2] == 16.5
    assert edited.station("index").target.axes[0] == 14.0
    assert showcase.number(LINKS) == before
    # The edited file reads back to the same design.
    assert fivebar.Design.from_yaml(edited.to_yaml()).number(LINKS) == 16.5


def test_a_broken_number_names_the_file_line_and_key():
    text = SHOWCASE.read_text()
    old = "links: [9, 9, 15, 15]"
    assert old in text
    broken = text.replace(old, "links: [9, 9, -15, 15]", 1)
    line = broken[: broken.index("links: [9, 9, -15, 15]")].count("\n") + 1
    with pytest.raises(fivebar.InputError) as err:
        fivebar.Design.from_yaml(broken, origin="broken.yaml")
    e = err.value
    assert isinstance(e, ValueError)
    assert e.file == "broken.yaml" and e.line == line
    assert e.key.endswith("links[2]"), e.key
    assert "-15" in str(e)


def test_bad_key_paths_and_files_raise_input_errors(showcase, tmp_path):
    with pytest.raises(fivebar.InputError, match=r"stations\.index\.nothing"):
        showcase.with_numbers({"stations.index.nothing": 1.0})
    with pytest.raises(fivebar.InputError, match=r"stations\.index\.nothing"):
        showcase.number("stations.index.nothing")
    with pytest.raises(fivebar.InputError, match="links"):
        showcase.with_numbers({LINKS: -1.0})
    missing = tmp_path / "missing.yaml"
    with pytest.raises(fivebar.InputError, match="missing.yaml"):
        fivebar.load(missing)
    with pytest.raises(fivebar.InputError, match="unknown station 'pinky'"):
        showcase.station("pinky")
    with pytest.raises(TypeError):
        fivebar.load(42)


def test_a_mechanism_built_by_hand_is_validated():
    m = fivebar.Mechanism(bases=((0, 0), (12.5, 0)), links=(9, 9, 15, 15))
    assert m.links == (9.0, 9.0, 15.0, 15.0)
    with pytest.raises(fivebar.InputError, match=r"links\[1\]"):
        fivebar.Mechanism(bases=((0, 0), (12.5, 0)), links=(9, -9, 15, 15))
    with pytest.raises(fivebar.InputError, match="working_mode"):
        fivebar.Mechanism(bases=((0, 0), (12.5, 0)), links=(9, 9, 15, 15), working_mode="x")


def test_version_is_the_one_of_cmakelists():
    """One version for the project: CMakeLists.txt's project(VERSION), read here from the file."""
    import re
    from conftest import ROOT
    text = (ROOT / "CMakeLists.txt").read_text()
    version = re.search(r"project\(fivebar\s+VERSION\s+([0-9.]+)", text).group(1)
    assert fivebar.__version__ == version == fivebar.version()
    assert "__version__" in fivebar.__all__


def test_a_mechanism_with_the_wrong_count_says_what_it_expects():
    bases = ((0.0, 0.0), (12.5, 0.0))
    with pytest.raises(fivebar.InputError, match=r"links: expected 4 lengths \(L1, L2, L3, L4\) in mm, got 3"):
        fivebar.Mechanism(bases=bases, links=[9, 9, 15])
    with pytest.raises(fivebar.InputError, match=r"links: expected 4 lengths .* got a float"):
        fivebar.Mechanism(bases=bases, links=9.0)
    with pytest.raises(fivebar.InputError, match=r"links\[2\]: expected a number, got a str"):
        fivebar.Mechanism(bases=bases, links=[9, 9, "15", 15])
    with pytest.raises(fivebar.InputError, match=r"bases: expected 2 base joints .* got 1"):
        fivebar.Mechanism(bases=[(0.0, 0.0)], links=[9, 9, 15, 15])
    with pytest.raises(fivebar.InputError, match=r"bases\[1\]: expected 2 numbers, got 3"):
        fivebar.Mechanism(bases=[(0.0, 0.0), (12.5, 0.0, 1.0)], links=[9, 9, 15, 15])
    with pytest.raises(fivebar.InputError, match=r"joint_limits: expected 2 ranges"):
        fivebar.Mechanism(bases=bases, links=[9, 9, 15, 15], joint_limits=[(0.0, 1.0)])
    # The same numbers in the right shape build the paper's index mechanism.
    m = fivebar.Mechanism(bases=bases, links=[9, 9, 15, 15])
    assert m.links == (9.0, 9.0, 15.0, 15.0)


def test_a_mistyped_key_path_names_the_nearest_key(showcase):
    with pytest.raises(fivebar.InputError, match=r"has no key 'linkz' \(did you mean 'links'\?\)"):
        showcase.with_numbers({"stations.index.mechanisms.lower.linkz[2]": 16.0})
    with pytest.raises(fivebar.InputError, match=r"has no key 'indx' \(did you mean 'index'\?\)"):
        showcase.number("stations.indx.mechanisms.lower.links[2]")
    # Nothing near: no suggestion.
    with pytest.raises(fivebar.InputError) as e:
        showcase.number("stations.index.zzzzzzzz")
    assert "did you mean" not in str(e.value)


def test_every_public_name_has_a_type_stub():
    import ast
    import pathlib
    stub = pathlib.Path(fivebar.__file__).with_name("__init__.pyi")
    names = set()
    for node in ast.parse(stub.read_text()).body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
            names.add(node.target.id)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets if isinstance(t, ast.Name))
        elif isinstance(node, ast.ImportFrom):
            names.update(a.asname or a.name for a in node.names)
    missing = [n for n in fivebar.__all__ if n not in names]
    assert not missing, f"fivebar.__all__ names without a stub in {stub.name}: {missing}"
