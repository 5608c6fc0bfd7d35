"""Figure ``flat-swatches``: the reflector in three colours side by side."""

from envstudio.plugin import Figure, FigureRequest, tile, write_image

SWATCH_COLOURS = ((0.8, 0.1, 0.1), (0.1, 0.8, 0.1), (0.1, 0.1, 0.8))


def draw_swatches(request: FigureRequest) -> list[str]:
    """Render the reflector once per colour of :data:`SWATCH_COLOURS`, write them in a row."""
    method = request.method("flat")
    panels = []
    for colour in SWATCH_COLOURS:
        method.values["colour"] = colour
        request.session.render_offscreen(method, request.size)
        panels.append(request.session.read_ldr())
    write_image(request.output, tile([panels]))
    return [f"{request.output}: the reflector in red, green and blue"]


SWATCHES = Figure("flat-swatches", "the reflector in three colours (plugin example)", draw_swatches)
