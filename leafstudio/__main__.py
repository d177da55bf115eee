"""`python -m leafstudio` runs the command line."""

from leafstudio.cli import main

raise SystemExit(main())
