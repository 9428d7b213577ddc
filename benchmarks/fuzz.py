"""Fuzz every reader through its command: mutated real files, outcomes counted.

    python benchmarks/fuzz.py [--cases 2100] [--seed 0] [--workers 1] [--timeout 60]

Each case mutates one real file (``../shared/data``'s C3D, video, BVH, ASF/AMC; the
shipped cmu41 marker set TOML; an annotations JSON of the sample walk) once -
truncation, byte flips, a C3D header or parameter field set to an extreme, a number
made absurd, a line dropped or repeated - and runs the command that reads it in a
child process under a 3 GiB address-space cap and a timeout (tests/hostile/fuzzing.py).
The table counts outcomes per format: a clean one-line error naming the file (exit 2)
and success are allowed; crash (a signal), hang (the timeout), traceback (or any
unclean failure), input changed and stray file must all be 0.

The reference measured in the same run is the unmutated file through the same command
(its time per case), so the mutants' cost reads as a ratio under any machine load.
"""

from __future__ import annotations

import argparse
import collections
import multiprocessing
import os
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.hostile.fuzzing import mutation_plan, preload, run_case, targets  # noqa: E402
from tests.hostile.mutate import OUTCOMES  # noqa: E402

BAD = OUTCOMES[2:]


def _work(job):
    (k, n, seed, timeout, root) = job
    out = []
    for i, (t, m, rng) in enumerate(mutation_plan(n, seed)):
        if i % k[1] != k[0]:
            continue
        got, run, folder = run_case(t, m, rng, root=Path(root), timeout=timeout)
        note = ""
        if got in BAD:
            note = f"{t.name} {t.source.name} {getattr(m, '__name__', 'mutation')}: {got}" \
                   f" rc={run.returncode} {run.stderr.strip()[-300:]!r} ({folder})"
        else:
            _clean(folder)
        out.append((t.name, got, run.seconds, note))
    return out


def _clean(folder: Path) -> None:
    import shutil

    shutil.rmtree(folder, ignore_errors=True)


def _reference(root: Path, timeout: float) -> dict[str, float]:
    """Seconds per unmutated case per format (the same commands on the real files)."""
    import numpy as np

    times = collections.defaultdict(list)
    for t in targets():
        got, run, folder = run_case(t, lambda d, r: d, np.random.default_rng(0), root=root,
                                    timeout=timeout)
        times[t.name].append(run.seconds)
        _clean(folder)
    return {k: sum(v) / len(v) for k, v in times.items()}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=2100)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=1,
                    help="parallel case runners (the machine is shared: default 1)")
    ap.add_argument("--timeout", type=float, default=60.0)
    args = ap.parse_args()
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    preload()
    root = Path(tempfile.mkdtemp(prefix="vidcap-fuzz-"))
    t0 = time.monotonic()
    ref = _reference(root, args.timeout)
    jobs = [((k, args.workers), args.cases, args.seed, args.timeout, str(root))
            for k in range(args.workers)]
    if args.workers == 1:
        results = [_work(jobs[0])]
    else:
        with multiprocessing.get_context("fork").Pool(args.workers) as pool:
            results = pool.map(_work, jobs)
    rows = [r for part in results for r in part]
    wall = time.monotonic() - t0

    table = collections.defaultdict(collections.Counter)
    secs = collections.defaultdict(list)
    for fmt, got, s, _ in rows:
        table[fmt][got] += 1
        secs[fmt].append(s)
    head = f"{'format':10s} {'cases':>6s} " + " ".join(f"{c:>13s}" for c in OUTCOMES) + \
        f" {'s/case':>7s} {'ref s':>6s}"
    print(f"fuzz: {len(rows)} mutated inputs, seed {args.seed}, cap 3 GiB, timeout"
          f" {args.timeout:g} s, {wall:.0f} s wall")
    print(head)
    total = collections.Counter()
    for fmt in sorted(table):
        c = table[fmt]
        total.update(c)
        mean = sum(secs[fmt]) / len(secs[fmt])
        print(f"{fmt:10s} {sum(c.values()):6d} " + " ".join(f"{c[o]:13d}" for o in OUTCOMES)
              + f" {mean:7.2f} {ref.get(fmt, float('nan')):6.2f}")
    print(f"{'all':10s} {sum(total.values()):6d} " + " ".join(f"{total[o]:13d}" for o in OUTCOMES))
    bad = [note for *_, note in rows if note]
    for note in bad[:30]:
        print("  " + note)
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
