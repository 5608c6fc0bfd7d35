"""PyInstaller hook for imgui-bundle: its extension, libglfw and the fonts, not the demos."""

from PyInstaller.utils.hooks import collect_data_files, collect_dynamic_libs

binaries = collect_dynamic_libs("imgui_bundle")
datas = collect_data_files(
    "imgui_bundle",
    excludes=["demos_assets", "demos_cpp", "demos_python", "**/*.pyi", "**/*.md"],
)
