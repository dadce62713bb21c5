"""Entry point: ``python -m prima.sim`` (its commands read scenario files: they live in
:mod:`prima.scenario`, which the simulator itself never imports)."""

import sys

from prima.scenario import main

sys.exit(main())
