"""Serve the annotate page on a synthetic clip (test-only data): for the page's own tests.

    python tests/ui/serve_fake.py --port 8080 --annotations /tmp/a.json
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parents[2]), str(Path(__file__).parent)]

from fakes import FakeAnnotations, FakeLifter, synthetic_clip  # noqa: E402

from ui.annotate import serve  # noqa: E402
from ui.session import AnnotateSession  # noqa: E402

if __name__ == "__main__":
    p = argparse.ArgumentParser()
    p.add_argument("--port", type=int, default=0)
    p.add_argument("--annotations", required=True)
    a = p.parse_args()
    session = AnnotateSession(synthetic_clip(), a.annotations, lifter=FakeLifter(),
                              annotations_cls=FakeAnnotations)
    sys.argv = sys.argv[:1]
    serve(session, port=a.port, open_browser=False)
