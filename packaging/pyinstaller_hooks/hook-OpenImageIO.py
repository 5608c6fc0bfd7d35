"""PyInstaller hook for OpenImageIO: the module, its libOpenImageIO* and fonts, not its tools."""

from PyInstaller.utils.hooks import collect_data_files, collect_dynamic_libs

binaries = collect_dynamic_libs("OpenImageIO", search_patterns=["*.so", "*.so.*"])
datas = collect_data_files("OpenImageIO", excludes=["bin", "**/*.pyi"])
