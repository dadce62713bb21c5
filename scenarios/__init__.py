"""The scenarios shipped with PRIMA and their maps (``scenarios/maps``), with their golden
traces, as package data (``prima.scenarios``; prima.shipped finds them)."""
