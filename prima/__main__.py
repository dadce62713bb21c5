"""``python -m prima``: the same as the ``prima`` command."""

import sys

from prima.cli import main

sys.exit(main())
