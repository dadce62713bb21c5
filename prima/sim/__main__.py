"""Entry point: ``python -m prima.sim``."""

import sys

from prima.sim.cli import main

sys.exit(main())
