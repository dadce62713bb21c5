"""A run as an MCAP recording, to open in Foxglove: ``prima run --format mcap``.

The map as a 3D scene, the robot and the user as moving frames and poses,
the words said as log lines, each device's atomic behaviors and each
application's PXML state as state changes, every decision of the mediator
with its reason, and the judge's findings; :data:`TOPICS` lists them. Messages
use Foxglove's well-known schemas (``foxglove.SceneUpdate``,
``foxglove.FrameTransforms``, ``foxglove.PoseInFrame``, ``foxglove.PosesInFrame``,
``foxglove.Log``) where one fits, and named JSON schemas (``prima.Decision``,
...) for PRIMA's own. ``docs/running.md`` says which Foxglove panels show what.

An exporter, apart from the core: only ``prima run --format mcap`` imports it,
and it needs the ``mcap`` extra (``pip install 'prima[mcap]'``: foxglove-sdk,
which writes MCAP with those schemas).
"""

from prima.mcap._recorder import TOPICS, Recorder

__all__ = ["TOPICS", "Recorder"]
