"""A live run on Foxglove's WebSocket protocol (foxglove-sdk's server).

The same channels, topics and schemas as the MCAP recording (:class:`prima.mcap.Recorder`,
writing to no file, on the server's context): each trace line is logged as the run
makes it, stamped with simulated time, which the server also broadcasts as its time.
A client that subscribes to the map, the bodies or the paths after the start gets them
again at once. The judge's findings are logged as they become final (``/judge``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import foxglove
from foxglove.websocket import Capability, ChannelView, Client, ServerListener

from prima.errors import PrimaError
from prima.mcap import Recorder
from prima.sim import WorldMap
from prima.trace import TraceLine

__all__ = ["FoxgloveLive"]

_AGAIN = frozenset({"/map", "/bodies", "/robot/path", "/user/path"})
"""What a client that subscribes late is sent again at once."""


class _Listener(ServerListener):
    """Notes a late subscription to what a client should have at once."""

    def __init__(self, live: FoxgloveLive) -> None:
        self.live = live

    def on_subscribe(self, _client: Client, channel: ChannelView) -> None:
        if channel.topic in _AGAIN:
            self.live.again = True


class FoxgloveLive:
    """A Foxglove WebSocket server showing one live run."""

    def __init__(self, world: WorldMap | None, *, host: str, port: int,
                 robot_radius: float = 0.2, name: str = "prima live") -> None:
        self.context = foxglove.Context()
        self.recorder = Recorder(None, world, robot_radius=robot_radius, context=self.context)
        self.again = False
        """A client subscribed to what it should have at once (set by the server's thread,
        done by the run's)."""
        try:
            self.server = foxglove.start_server(
                name=name, host=host, port=port, context=self.context,
                capabilities=[Capability.Time], server_listener=_Listener(self))
        except (RuntimeError, ValueError) as exc:  # (the port is taken, say)
            raise PrimaError(f"cannot serve Foxglove on {host}:{port}: "
                             f"{str(exc).removeprefix('FoxgloveError: ')}") from exc
        self.port = self.server.port
        self._sent_at = -1.0

    def line(self, line: TraceLine) -> None:
        """A trace line, from the run's thread (as it is made)."""
        recorder = self.recorder
        recorder.write(line)
        if self.again or line.t - self._sent_at >= 2.0:
            self.again = False
            self._sent_at = line.t
            recorder.scene_again()
            recorder.paths_so_far()
        self.server.broadcast_time(round(line.t * 1e9))

    def findings(self, found: Sequence[Mapping[str, Any]]) -> None:
        """Final findings of the judge (:class:`prima.live._judging.LiveJudge`)."""
        for f in found:
            self.recorder.finding(float(f["t"]), str(f["key"]), str(f["line"]))

    def layout(self) -> str:
        return self.recorder.layout()

    def stop(self) -> None:
        self.server.stop()
