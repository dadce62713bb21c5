"""The applications shipped with PRIMA (``apps/fa``: FAs, ``apps/ea``: EAs), as package
data (``prima.apps``; prima.shipped finds them)."""
