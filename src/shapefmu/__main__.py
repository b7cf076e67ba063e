"""``python -m shapefmu`` is the ``shapefmu`` command."""

from shapefmu.cli import main

raise SystemExit(main())
