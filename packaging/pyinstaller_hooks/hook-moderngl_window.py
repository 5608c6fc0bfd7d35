"""PyInstaller hook for moderngl-window: the glfw window envstudio opens, and its data."""

from PyInstaller.utils.hooks import collect_data_files

hiddenimports = ["moderngl_window.context.glfw", "moderngl_window.context.headless"]
datas = collect_data_files("moderngl_window")
