"""Serve the annotate page on a sample clip's ground truth (test-only stage results).

    python tests/ui/serve_truth.py --port 8080 --annotations /tmp/a.json [--clip walk_side]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parents[2]), str(Path(__file__).parent)]

from clips import truth_clip  # noqa: E402

from ui.annotate import serve  # noqa: E402
from ui.session import AnnotateSession  # noqa: E402

if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--port", type=int, default=0)
    p.add_argument("--annotations", required=True)
    p.add_argument("--clip", default="walk_side")
    a = p.parse_args()
    session = AnnotateSession(truth_clip(a.clip), a.annotations)
    serve(session, port=a.port, open_browser=False)
