"""The README's Python example runs, and its gradient is a slope: the
autodiff Jacobian it prints matches central differences (`gradcheck` "ok")."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(), flags=re.S)


@pytest.mark.parametrize("page", ["README.md"])  # the docs page shows the same example
def test_gradient_examples_match_central_differences(page, capsys):
    blocks = [b for b in _python_blocks(ROOT / page) if "gradcheck" in b]
    assert blocks, f"{page}: no Python example with diffwear.gradcheck"
    for code in blocks:
        namespace: dict = {}
        exec(compile(code, page, "exec"), namespace)  # noqa: S102 - our own docs
        printed = capsys.readouterr().out
        assert "ok: autodiff matches central differences" in printed, printed
