"""``prima check``: an EA judged beside every FA and robot it may meet, at any timing.

:func:`check` runs the matrix (rows FA, columns robot), each cell on the EA's own
scenarios or on generated visits, each swept with jittered timings through
:mod:`prima.batch`; every failure is attributed to the application whose doing it
is; the EA's coverage says what of it ran. :func:`format_check`, :func:`junit` and
:func:`markdown` show the outcome. Imported only by the command that needs it.
"""

from prima.check._check import Cell, Check, Failure, Verdict, check
from prima.check._coverage import KINDS, Coverage, Item
from prima.check._observe import CheckAnalysis, attribute
from prima.check._report import format_check, format_coverage, junit, markdown
from prima.check._places import Destination, destinations, map_for
from prima.check._visits import (
    VISITS,
    Visit,
    beside,
    listens,
    questions,
    sends,
    starts,
    visit_scenario,
)

__all__ = ["KINDS", "VISITS", "Cell", "Check", "CheckAnalysis", "Coverage", "Destination",
           "Failure", "Item", "Verdict", "Visit", "attribute", "beside", "check",
           "destinations", "format_check", "format_coverage", "junit", "listens", "map_for",
           "markdown", "questions", "sends", "starts", "visit_scenario"]
