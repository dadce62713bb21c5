"""A run as an MCAP recording, to open in Foxglove: ``prima run --format mcap``.

The map as a 3D scene, the robot and the user as moving frames and poses,
the words said as log lines, each device's atomic behaviors and each
application's PXML state as state changes, every decision of the mediator
with its reason, and the judge's findings; :data:`TOPICS` lists them. Messages
use Foxglove's well-known schemas (``foxglove.SceneUpdate``,
``foxglove.FrameTransforms``, ``foxglove.PoseInFrame``, ``foxglove.PosesInFrame``,
``foxglove.Log``) where one fits, and named JSON schemas (``prima.Decision``,
...) for PRIMA's own. ``docs/running.md`` says which Foxglove panels show what.

A recording carries its run's Foxglove layout (:func:`layout`: a 3D panel, the device
timeline, the words, the decisions, the findings) as its attachment :data:`ATTACHMENT`;
the layout for the home robot ships as a file (:func:`shipped`). The same channels
serve a live run (``prima live --foxglove``: a :class:`Recorder` of no file, on the
WebSocket server's context).

An exporter, apart from the core: only ``prima run --format mcap`` imports it,
and it needs the ``mcap`` extra (``pip install 'prima[mcap]'``: foxglove-sdk,
which writes MCAP with those schemas).
"""

from prima.mcap._layout import ATTACHMENT, HOME_DEVICES, layout, shipped
from prima.mcap._recorder import TOPICS, Recorder

__all__ = ["ATTACHMENT", "HOME_DEVICES", "TOPICS", "Recorder", "layout", "shipped"]
