"""README's Python example runs as written and does what its comment says."""

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_example_runs():
    (code,) = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    namespace = {}
    exec(compile(code, "README.md", "exec"), namespace)  # noqa: S102 - our own documentation
    from activecontour import synthetic

    assert synthetic.dice(namespace["res"].mask, namespace["truth"]) >= 0.98  # README says ~0.99
