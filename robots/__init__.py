"""Robot hardware profiles shipped with PRIMA, as package data (``prima.robots``)."""
