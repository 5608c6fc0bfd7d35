"""OpenGL plumbing: contexts, shader loading, render targets, timers, GPU meshes."""
