"""Every stored record a page reads carries the provenance stamp, or is listed with what remakes
it (issue 51 item 4): tests/data/doc_records.toml is checked against docs/ both ways, so a new
unstamped record fails here, and so does a restamped one still listed as unstamped. Reads JSON
only; no run.
"""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
LIST = ROOT / "tests" / "data" / "doc_records.toml"
SUFFIXES = {".json", ".csv", ".npz"}
#: the libraries that build the matrices and meshes must be in a stamp (the run key's format 4)
NEEDED_LIBRARIES = {"scikit-fem", "gmsh"}


def is_stamp(d) -> bool:
    """d is a provenance stamp (flexmvm.runs.provenance.stamp or script_stamp)."""
    return (
        isinstance(d, dict)
        and {"key", "code", "libraries"} <= set(d)
        and isinstance(d["libraries"], dict)
        and NEEDED_LIBRARIES <= set(d["libraries"])
    )


def has_stamp(d) -> bool:
    if is_stamp(d):
        return True
    if isinstance(d, dict):
        return any(has_stamp(v) for v in d.values())
    if isinstance(d, list):
        return any(has_stamp(v) for v in d)
    return False


def json_stamped(path: Path) -> bool:
    try:
        return has_stamp(json.loads(path.read_text()))
    except (OSError, ValueError):
        return False


def stamped(path: Path) -> bool:
    """A JSON record with a stamp inside it, a record in a run folder with a stamped key.json,
    or a table/curve file beside a stamped JSON whose name begins its name."""
    if path.suffix == ".json" and json_stamped(path):
        return True
    key = path.parent / "key.json"
    if key.exists() and json_stamped(key):
        return True
    if path.suffix != ".json":
        return any(
            path.stem.startswith(side.stem) and json_stamped(side)
            for side in path.parent.glob("*.json")
        )
    return False


def doc_records() -> list[str]:
    notes, build = DOCS / "notes", DOCS / "_build"
    return sorted(
        str(p.relative_to(ROOT))
        for p in DOCS.rglob("*")
        if p.suffix in SUFFIXES and notes not in p.parents and build not in p.parents
    )


def listed() -> dict:
    with open(LIST, "rb") as f:
        return tomllib.load(f)


def test_every_record_is_stamped_covered_or_listed():
    lists = listed()
    covered, unstamped = lists["covered"], lists["unstamped"]
    loose = [
        r
        for r in doc_records()
        if not stamped(ROOT / r) and r not in covered and r not in unstamped
    ]
    assert not loose, f"records in docs/ without a provenance stamp: {loose}"


def test_listed_records_exist_and_are_what_the_list_says():
    lists = listed()
    records = set(doc_records())
    gone = [r for r in [*lists["covered"], *lists["unstamped"]] if r not in records]
    assert not gone, f"listed in {LIST.name} but not in docs/: {gone}"
    restamped = [r for r in lists["unstamped"] if stamped(ROOT / r)]
    assert not restamped, f"stamped now: take them off [unstamped] in {LIST.name}: {restamped}"
    for record, by in lists["covered"].items():
        if by.startswith("docs/"):
            assert stamped(ROOT / by), f"{record} is covered by {by}, which has no stamp"


def test_stamp_rule_tells_a_full_stamp_from_an_old_one():
    """A format-2 stamp (before scikit-fem and gmsh were in the key) is not a full stamp."""
    full = {
        "key": "k",
        "code": "c",
        "libraries": {"scikit-fem": "10", "gmsh": "4.13", "numpy": "2"},
    }
    old = {"key": "k", "code": "c", "libraries": {"numpy": "2", "scipy": "1.14"}}
    assert has_stamp({"rows": [{"provenance": full}]})
    assert not has_stamp({"rows": [{"provenance": old}], "commit": "abc"})
