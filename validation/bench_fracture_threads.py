"""Fracture events per second with the BLAS threads capped (the default, one thread)
and left to the library, on a quiet machine and beside a busy process.

The event loop's dense algebra is small (the low-rank updates' capacitance solves, a few
hundred columns): on a shared 2-core machine the threads fight for the cores. The run is
Petersson's notched beam (validation/fracture.py) with ``max_rank`` columns of updates
between factorisations; "busy" runs it beside one process spinning on a core. Each
configuration runs in a fresh process (the BLAS pools are per process) and reports
events per second of the loop and the CPU seconds it used.

Usage::

    python validation/bench_fracture_threads.py           # 5.0e3, 9.8e3 and 9.6e4 nodes
    python validation/bench_fracture_threads.py --quick   # h = 20 mm (1.3e3 nodes)

The sizes: h = 10 mm CVT (5,019 nodes, 1,500 events), and the two runs of
``fracture.py``'s speed table, h = 7 mm (9,780 nodes, 300 events) and 2.2 mm (96,471
nodes, 100 events), jittered.

Writes ``validation/out/bench_fracture_threads.json`` and prints a table.
"""

from __future__ import annotations

import json
import multiprocessing as mp
import subprocess
import sys
import time
from pathlib import Path

from _common import parser, write_json

HERE = Path(__file__).resolve().parent

ONE_RUN = """
import json, resource, sys, time
sys.path.insert(0, {here!r})
import logging; logging.disable(logging.WARNING)
from fracture import petersson_run
threads = None if {threads!r} == "library" else 1
t0 = time.process_time()
res = petersson_run({h}, kind={kind!r}, max_events={events}, stop_load_ratio=0.0,
                    max_rank=240, blas_threads=threads)
print(json.dumps({{"events": len(res.events), "loop_seconds": res.seconds.events,
                  "events_per_second": res.stats.events_per_second,
                  "cpu_seconds": time.process_time() - t0,
                  "nodes": res.model.mesh.n_points}}))
"""


def _spin(stop) -> None:
    while not stop.is_set():
        pass


#: (h in mm, mesh kind, events) of the full and the quick run
SIZES = ((10.0, "cvt", 1500), (7.0, "jittered", 300), (2.2, "jittered", 100))
QUICK = ((20.0, "cvt", 400),)


def run(h: float, kind: str, events: int, threads: str, busy: bool) -> dict:
    code = ONE_RUN.format(here=str(HERE), threads=threads, h=h, kind=kind, events=events)
    stop = mp.Event()
    hog = mp.Process(target=_spin, args=(stop,)) if busy else None
    if hog is not None:
        hog.start()
        time.sleep(0.5)
    try:
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    finally:
        if hog is not None:
            stop.set()
            hog.join()
    if out.returncode != 0:
        raise RuntimeError(out.stderr)
    rec = json.loads(out.stdout.strip().splitlines()[-1])
    return {"threads": threads, "machine": "busy" if busy else "quiet", "h": h, "kind": kind, **rec}


def main(argv=None) -> int:
    args = parser(__doc__).parse_args(argv)
    rows = []
    for h, kind, events in QUICK if args.quick else SIZES:
        for busy in (False, True):
            for threads in ("library", "1"):
                rows.append(run(h, kind, events, threads, busy))
                _print(rows[-1])
    data = {"quick": args.quick, "sizes": QUICK if args.quick else SIZES, "rows": rows}
    out = write_json(data, args.out / "bench_fracture_threads.json")
    print(f"wrote {out}")
    return 0


def _print(r: dict) -> None:
    print(
        f"{r['machine']:6s} BLAS threads {r['threads']:8s} {r['nodes']:6d} nodes "
        f"{r['events']:5d} events: {r['events_per_second']:7.1f} events/s, "
        f"CPU {r['cpu_seconds']:6.2f} s",
        flush=True,
    )


if __name__ == "__main__":
    raise SystemExit(main())
