"""A Foxglove layout for PRIMA's topics (foxglove-sdk's ``foxglove.layouts``).

Three columns: on the left a 3D panel in the frame ``map`` with the map, the robot,
the user and their paths; in the middle the device timeline as state transitions (one
row per device, and one per application's PXML state); on the right the words said,
the mediator's latest decision and the judge's findings. A recording carries the
layout of its run (an MCAP attachment, :data:`ATTACHMENT`); ``prima live --foxglove``
serves its own; the layout for the home robot's devices ships as
``prima/mcap/foxglove-layout.json`` (:func:`shipped`).
"""

from __future__ import annotations

from collections.abc import Sequence

import foxglove.layouts as fl

from prima.shipped import packaged

__all__ = ["ATTACHMENT", "HOME_DEVICES", "layout", "shipped"]

ATTACHMENT = "foxglove-layout.json"
"""The name of a recording's layout among its attachments (and of the shipped file)."""

HOME_DEVICES = ("speaker", "speech-recognition", "locomotion", "human-detection",
                "localization", "neck", "arm")
"""The home robot's devices, in the order the device timeline usually shows them."""


def layout(devices: Sequence[str] = HOME_DEVICES, apps: Sequence[str] = ()) -> fl.Layout:
    """The layout for a run on a robot with these devices, of these applications."""
    scene = fl.ThreeDeePanel(title="the building from above", config=fl.ThreeDeeConfig(
        follow_tf="map", fixed_frame="map",
        camera_state=fl.ThreeDeeCameraState(distance=25.0, perspective=False, phi=0.0,
                                            target=(8.0, 5.0, 0.0)),
        topics={
            "/map": fl.BaseRendererSceneUpdateTopicSettings(visible=True),
            "/bodies": fl.BaseRendererSceneUpdateTopicSettings(visible=True),
            "/robot/path": fl.BaseRendererPosesTopicSettings(visible=True, type="line",
                                                             line_width=0.05,
                                                             gradient=("#2c3e50", "#2c3e50")),
            "/user/path": fl.BaseRendererPosesTopicSettings(visible=True, type="line",
                                                            line_width=0.05,
                                                            gradient=("#e67e22", "#e67e22")),
        }))
    timeline = fl.StateTransitionsPanel(title="devices", config=fl.StateTransitionsConfig(
        paths=[fl.StateTransitionsSeries(value=f"/devices/{d}.state", label=d)
               for d in devices], show_points=True))
    items = [fl.SplitItem(proportion=3, content=timeline)]
    if apps:
        items.append(fl.SplitItem(proportion=1, content=fl.StateTransitionsPanel(
            title="applications", config=fl.StateTransitionsConfig(
                paths=[fl.StateTransitionsSeries(value=f"/apps/{a}/state.state", label=a)
                       for a in apps]))))
    words = fl.LogPanel(title="words", config=fl.LogConfig(topic_to_render="/words",
                                                           show_name=True))
    decisions = fl.RawMessagesPanel(title="decisions", config=fl.RawMessagesConfig(
        topic_path="/mediator", expansion="all"))
    findings = fl.LogPanel(title="the judge's findings", config=fl.LogConfig(
        topic_to_render="/judge", show_name=True))
    return fl.Layout(content=fl.SplitContainer(direction="row", items=[
        fl.SplitItem(proportion=2, content=scene),
        fl.SplitItem(proportion=2, content=fl.SplitContainer(direction="column", items=items)),
        fl.SplitItem(proportion=2, content=fl.SplitContainer(direction="column", items=[
            fl.SplitItem(proportion=2, content=words),
            fl.SplitItem(proportion=2, content=decisions),
            fl.SplitItem(proportion=1, content=findings)])),
    ]))


def shipped() -> str:
    """The shipped layout file's text (the home robot's devices; no application rows)."""
    return packaged("prima.mcap", ATTACHMENT).read_text(encoding="utf-8")
