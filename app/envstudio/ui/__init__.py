"""The moderngl-window + imgui-bundle desktop application."""
