"""``prima live``: play the user of your applications in the browser, in real time.

A :class:`Session` runs a scenario (or applications alone) paced to a wall clock
(:class:`LiveClock`); what the author does from the page (say, touch, walk, follow,
stop, a network message) is given to the simulator at the tick after the one they
saw, the way a scenario's own inputs are, and kept: :meth:`Session.saved` is a
scenario that ``prima run`` replays to the same trace. The server
(:func:`serve`) shows it on one local page, with the judge's findings as they become
final; ``--foxglove`` serves the same run to Foxglove.

A viewer and a server, apart from the core: only ``prima live`` imports it, and it
needs the ``live`` extra (``pip install 'prima[live]'``: aiohttp and Plotly).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from prima.live._clock import MAX_SPEED, LiveClock
    from prima.live._command import Options, base_of, serve
    from prima.live._judging import LiveJudge, final
    from prima.live._scenario import ACTIONS, Added, Base, for_apps, from_scenario
    from prima.live._server import Hints, SaveTo, Server, check_save
    from prima.live._session import LiveError, Session, Stopped

__all__ = ["ACTIONS", "MAX_SPEED", "Added", "Base", "Hints", "LiveClock", "LiveError",
           "LiveJudge", "Options", "SaveTo", "Server", "Session", "Stopped", "base_of",
           "check_save", "final", "for_apps", "from_scenario", "serve"]

_WHERE = {
    **dict.fromkeys(("MAX_SPEED", "LiveClock"), "_clock"),
    **dict.fromkeys(("Options", "base_of", "serve"), "_command"),
    **dict.fromkeys(("LiveJudge", "final"), "_judging"),
    **dict.fromkeys(("ACTIONS", "Added", "Base", "for_apps", "from_scenario"), "_scenario"),
    **dict.fromkeys(("Hints", "SaveTo", "Server", "check_save"), "_server"),
    **dict.fromkeys(("LiveError", "Session", "Stopped"), "_session"),
}


def __getattr__(name: str) -> object:
    """Each part is imported when first used: the clock's bound, which the command line
    checks, needs neither aiohttp nor the simulator."""
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value
