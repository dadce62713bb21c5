"""Robot hardware profiles shipped with PRIMA, as package data (``prima.robots``;
prima.shipped finds them)."""
