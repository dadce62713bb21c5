"""Names as the pictures show them: light, so the package and its drawing (which needs
matplotlib) both import it without importing each other."""

from __future__ import annotations

__all__ = ["abbreviate"]


def abbreviate(command: str, parts: int = 2) -> str:
    """A grouped AB's name shortened: ``Speak+Gesture+PointByHand`` -> ``Speak+Gesture+...``."""
    names = command.split("+")
    if len(names) <= parts:
        return command
    return "+".join(names[:parts]) + "+..."
