"""``python -m jaxplan.cli``: the ``jaxplan`` command."""

from jaxplan.cli import main

raise SystemExit(main())
