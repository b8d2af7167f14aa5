"""`import dvstatic` is light: no scipy, scikit-fem, matplotlib, meshio, pyamg or tqdm
(its time is a benchmark's to measure, not a test's: a wall-clock bound tripped on a
loaded machine, 0.60 s against 0.3 s)."""

import json
import subprocess
import sys

CODE = (
    "import sys, json; import dvstatic; "
    "print(json.dumps({'modules': [m for m in ('scipy', 'skfem', "
    "'matplotlib', 'meshio', 'pyamg', 'tqdm') if m in sys.modules]}))"
)


def test_import_is_light():
    out = subprocess.run(
        [sys.executable, "-c", CODE], capture_output=True, text=True, check=True
    ).stdout
    assert json.loads(out)["modules"] == [], out
