"""`import dvstatic` is light: no scipy, scikit-fem, matplotlib or meshio, under 0.3 s."""

import json
import subprocess
import sys

CODE = (
    "import sys, time, json; t = time.perf_counter(); import dvstatic; "
    "dt = time.perf_counter() - t; "
    "print(json.dumps({'seconds': dt, 'modules': [m for m in ('scipy', 'skfem', "
    "'matplotlib', 'meshio', 'pyamg', 'tqdm') if m in sys.modules]}))"
)


def test_import_is_light():
    runs = [
        json.loads(
            subprocess.run(
                [sys.executable, "-c", CODE], capture_output=True, text=True, check=True
            ).stdout
        )
        for _ in range(3)
    ]
    assert all(r["modules"] == [] for r in runs), runs
    # the fastest of three runs (process start-up noise on a busy machine)
    assert min(r["seconds"] for r in runs) < 0.3, runs
