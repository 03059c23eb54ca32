"""`python -m herringbone.cli ARGS`: the `herringbone` command."""
import sys

from . import main

sys.exit(main())
