"""What the C3D reader's safety costs: checks in Python plus ezc3d in a forked child.

    python benchmarks/c3d_read.py [--repeat 5]

For each real C3D file in ``../shared/data/c3d`` (those ezc3d reads), the median time
of: ezc3d in this process (the reference, what ``read_c3d`` did before), the header and
parameter checks alone (:func:`vidcap.mocap.c3dcheck.check_c3d`), ezc3d in a forked
child (:func:`vidcap.mocap.c3dchild.read_isolated`) and the whole :func:`read_c3d`.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
DATA = REPO.parent / "shared" / "data" / "c3d"


def _median_ms(fn, arg, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn(arg)
        times.append(time.perf_counter() - t)
    return 1000 * statistics.median(times)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    from vidcap.mocap.c3d import read_c3d
    from vidcap.mocap.c3dcheck import check_c3d
    from vidcap.mocap.c3dchild import _parse, read_isolated

    print(f"{'file':28s} {'kB':>6s} {'ezc3d ms':>9s} {'checks':>7s} {'forked':>7s}"
          f" {'read_c3d':>9s} {'ratio':>6s}")
    for path in sorted(DATA.glob("*.c3d")):
        try:
            _parse(str(path))
        except Exception:  # noqa: BLE001 - the malformed-on-purpose file
            continue
        ref = _median_ms(lambda p: _parse(str(p)), path, args.repeat)
        chk = _median_ms(check_c3d, path, args.repeat)
        iso = _median_ms(read_isolated, path, args.repeat)
        full = _median_ms(read_c3d, path, args.repeat)
        print(f"{path.name:28s} {path.stat().st_size // 1024:6d} {ref:9.1f} {chk:7.1f}"
              f" {iso:7.1f} {full:9.1f} {full / ref:6.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
