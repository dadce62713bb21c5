"""The ``prima`` command line: ``prima validate ...``.

``main(argv)`` returns the exit status and never raises for a user's mistake:
0 when all is well, 1 when an input has errors, 2 for a usage error.

One module per command (``_validate.py``, ``_run.py``, ...: its arguments and a call
into the library), named in :data:`NAMES` (imported when a command line names it);
what they share in ``_common.py`` (exit
statuses, colour, problems and usage errors worded) and ``_options.py`` (the arguments
several commands take, and their checks); ``prima run``'s trace formats in one table,
``_formats.py``. Nothing in the library imports this package.
"""

from prima.cli._main import NAMES, build_parser, command, main

__all__ = ["NAMES", "build_parser", "command", "main"]
