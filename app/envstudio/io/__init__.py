"""Files in and out: images (OpenImageIO), meshes (trimesh), scene files, atomic writes."""
