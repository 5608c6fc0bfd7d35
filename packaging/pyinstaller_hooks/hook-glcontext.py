"""PyInstaller hook for glcontext: ``default_backend()`` imports its backends by name."""

hiddenimports = ["glcontext.egl", "glcontext.x11", "glcontext.empty"]
