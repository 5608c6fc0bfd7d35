"""The common scene graph: plain data, no GL."""
