"""The product speaks of the product: no process history (tracker numbers,
work-session words, references to planning documents outside the
repository) in the code, tests, docs, benchmarks, studies, notebooks or the
README.  History lives in git and CHANGELOG.md; a benchmark record's
provenance stays in its JSON."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PLACES = ["src", "tests", "docs", "benchmarks", "design_studies", "notebooks", "README.md"]
SUFFIXES = {".py", ".md", ".toml", ".ipynb", ".txt", ".yml", ".yaml", ".cfg"}
# built from pieces so that this file does not match itself
FORBIDDEN = re.compile("|".join(["iss" + r"ue [0-9]", "iss" + "ue #", "sess" + r"ion [0-9]",
                                 "dig" + "est"]), flags=re.I)


def _files():
    for place in PLACES:
        path = ROOT / place
        if path.is_file():
            yield path
        elif path.is_dir():
            yield from (p for p in path.rglob("*") if p.is_file() and p.suffix in SUFFIXES
                        and ".ipynb_checkpoints" not in p.parts)


def test_no_process_history_in_the_product():
    hits = []
    for path in _files():
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            if FORBIDDEN.search(line):
                hits.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()[:100]}")
    assert not hits, "\n".join(hits)
