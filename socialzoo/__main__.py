"""`python -m socialzoo` runs the `socialzoo` command."""

from socialzoo.cli import main

raise SystemExit(main())
