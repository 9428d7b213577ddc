"""``python -m vidcap`` is the same as the ``vidcap`` command."""

from vidcap.cli import main

raise SystemExit(main())
