"""Accepting a request: checking it, then finding its before node (rule 3, 6).

The before node is decided in this order:

1. ``follows=X`` within ``end_grace`` of X's end: a child of X, in X's tree
   (rule ``end-event``; CS exceptions (a) and (b)).
2. As soon as possible: cancel the app's own not-yet-started work in trees
   that share a device with the request (a running feedback Command stops
   after its current iteration); the newest running AB there that shares a
   device, else the newest cancelled node, is the before node; with no such
   tree the request roots a new one (rule ``asap`` in every case).
3. After latest: the app's latest Command if still in working memory
   (rule ``after-latest``); inside an open stream or block, its tree even if
   the latest Command already finished (rule ``stream``); else a new tree
   (rule ``new-tree``).
"""

from __future__ import annotations

from dataclasses import dataclass

from prima.errors import MediationError
from prima.catalog import Catalog, CommandSpec
from prima.mediator.decisions import Rule
from prima.mediator.interface import AppKind, Request, RunningOrder
from prima.mediator.state import NodeState, _App, _Command, _Node, _Tree

__all__ = ["Link", "check_request", "link_after_latest"]

IN_MEMORY = (NodeState.PENDING, NodeState.WAITING, NodeState.RUNNING)


@dataclass
class Link:
    """Where a request's root goes."""

    rule: Rule
    parent: _Node | None = None
    tree: _Tree | None = None
    enter_now: bool = True
    """The root enters the waiting list at once (no before node still to run)."""
    parent_finished: bool = False
    """The root ranks as 'parent just finished'."""
    reactive_allowed: bool = True


def check_request(catalog: Catalog, apps: dict[str, _App],
                  request: Request) -> tuple[_App, list[tuple[CommandSpec, frozenset[str]]]]:
    """Validate a request before anything changes; returns the app and each call's spec/devices."""
    app = apps.get(request.app)
    if app is None:
        raise MediationError(f"unknown application {request.app!r}: register it first")
    if not request.calls:
        raise MediationError(f"{request.app}: a request needs at least one Command")
    if not isinstance(request.order, RunningOrder):
        raise MediationError(f"{request.app}: unknown running order {request.order!r}")
    out: list[tuple[CommandSpec, frozenset[str]]] = []
    for call in request.calls:
        spec = catalog.get(call.command)
        if spec is None:
            known = ", ".join(sorted(catalog.commands))
            raise MediationError(f"{request.app}: unknown Command {call.command!r} (known: {known})")
        if app.kind is AppKind.EA and spec.robot_specific:
            raise MediationError(
                f"{request.app}: {call.command} is robot-specific; only the FA may use it")
        if app.kind is AppKind.EA and call.extra:
            raise MediationError(
                f"{request.app}: additional arguments to {call.command} are FA-only")
        unknown = call.extra_devices - catalog.devices
        if unknown:
            raise MediationError(
                f"{request.app}: {call.command} names unknown devices {sorted(unknown)}")
        if request.group and spec.feedback and len(request.calls) > 1:
            raise MediationError(
                f"{request.app}: feedback Command {call.command} cannot be grouped into one AB "
                "(each loop iteration is its own AB)")
        out.append((spec, spec.devices | call.extra_devices))
    return app, out


def _continues(app: _App, tree: _Tree) -> bool:
    """An open stream or block of the app owns this tree."""
    st, blk = app.stream, app.block
    return ((st is not None and st.tree is tree)
            or (blk is not None and not blk.expired and blk.tree is tree))


def link_after_latest(app: _App) -> Link:
    """Rule 3, after latest (with the explicit-stream exception, rule 6c)."""
    latest: _Command | None = app.latest
    node = latest.node if latest is not None else None
    if node is not None and node.state in IN_MEMORY:
        return Link(Rule.AFTER_LATEST, node, node.tree, enter_now=False)
    if node is not None and _continues(app, node.tree):
        return Link(Rule.STREAM, node, node.tree, enter_now=True, parent_finished=True)
    return Link(Rule.NEW_TREE)
