"""PyInstaller hook for pyGLFW: the libglfw it loads through ctypes (x11/ and wayland/)."""

from PyInstaller.utils.hooks import collect_dynamic_libs

binaries = collect_dynamic_libs("glfw", search_patterns=["*.so", "*.so.*"])
