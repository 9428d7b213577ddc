"""glTF export: file size and write time of our numpy writer, against BVH and pygltflib.

    python benchmarks/gltf_export.py [--frames 300 1800] [--repeat 5]

For a motion of the body model's skeleton (seeded random joint turns, 30 fps), writes
with the Mixamo rig: BVH (the reference, measured in the same run), our .glb and .gltf,
and, when pygltflib is installed, the same glTF document built and saved as .glb by
pygltflib (``GLTF2.from_dict`` + ``set_binary_blob`` + ``save_binary``). Prints a table
of median write times (ms, and as a ratio of BVH's) and sizes (kB).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from vidcap.body import JOINT_NAMES, BodyModel  # noqa: E402
from vidcap.io.gltf import gltf_document  # noqa: E402
from vidcap.io.motionfile import write_motion  # noqa: E402
from vidcap.io.rigs import get_rig, retarget  # noqa: E402
from vidcap.kinematics import Motion  # noqa: E402


def _motion(n_frames: int) -> Motion:
    rng = np.random.default_rng(0)
    rv = rng.normal(scale=0.5, size=(n_frames * len(JOINT_NAMES), 3))
    q = Rotation.from_rotvec(rv).as_quat().reshape(n_frames, len(JOINT_NAMES), 4)
    root = np.cumsum(rng.normal(scale=0.01, size=(n_frames, 3)), axis=0)
    return Motion(BodyModel().skeleton(), root, q, 30.0)


def _pygltflib_glb(motion: Motion, path: Path) -> None:
    import pygltflib

    rig = get_rig("mixamo")
    doc, data = gltf_document(retarget(motion, rig), end_names=rig.end_site_names())
    g = pygltflib.GLTF2.from_dict(doc)
    g.set_binary_blob(data)
    g.save_binary(str(path))


def _time(fn, repeat: int) -> float:
    fn()  # warm up: first-call imports are not the writer's speed
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times) * 1e3


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, nargs="+", default=[300, 1800])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args(argv)
    try:
        import pygltflib  # noqa: F401
        have_pygltflib = True
    except ImportError:
        have_pygltflib = False
    print(f"{'frames':>6} {'writer':<22} {'ms':>8} {'x BVH':>7} {'kB':>8}")
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        for n in args.frames:
            m = _motion(n)
            def ours(p, m=m):
                return write_motion(p, m, rig="mixamo")

            rows = [("BVH (reference)", d / "m.bvh", ours), ("vidcap .glb", d / "m.glb", ours),
                    ("vidcap .gltf + .bin", d / "m.gltf", ours)]
            if have_pygltflib:
                rows.append(("pygltflib .glb", d / "p.glb",
                             lambda p, m=m: _pygltflib_glb(m, p)))
            ref = None
            for label, path, fn in rows:
                ms = _time(lambda fn=fn, path=path: fn(path), args.repeat)
                ref = ms if ref is None else ref
                size = sum(f.stat().st_size for f in (path, path.with_suffix(".bin"))
                           if f.exists() and (f == path or path.suffix == ".gltf"))
                print(f"{n:>6} {label:<22} {ms:>8.1f} {ms / ref:>7.2f} {size / 1e3:>8.1f}")
    if not have_pygltflib:
        print("(pygltflib is not installed: pip install pygltflib for its row)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
