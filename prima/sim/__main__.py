"""Entry point: ``python -m prima.sim``."""

import sys

from prima.sim import main

sys.exit(main())
