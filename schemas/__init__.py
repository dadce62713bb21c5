"""XSD schemas of PRIMA's documents, shipped as package data (``prima.schemas``)."""
