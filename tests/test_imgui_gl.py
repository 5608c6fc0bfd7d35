"""ImGui 1.92 renderer and input bridge on a headless context (llvmpipe without a GPU).

Every test drives real frames: ``ImGuiInput.prepare_frame`` → ``imgui.new_frame``
→ widgets → ``imgui.render`` → ``ImGuiRenderer.render`` into a 320×240
offscreen framebuffer, then reads the pixels back (row 0 = top, like ImGui).
"""

from __future__ import annotations

from collections.abc import Callable

import moderngl
import numpy as np
import pytest
from imgui_bundle import imgui
from moderngl_window.context.base import KeyModifiers
from moderngl_window.context.glfw.keys import Keys

from envstudio.ui.docking import PANEL_FLAGS, PANELS, DockLayout, ViewRect, gl_viewport
from envstudio.ui.imgui_input import ImGuiInput
from envstudio.ui.imgui_renderer import GLStateQuery, ImGuiRenderer

SIZE = (320, 240)
CLEAR = (32, 64, 96, 255)
WINDOW_POS = (10, 10)
WINDOW_SIZE = (200, 120)
LEFT_BUTTON = 1  # moderngl-window's MouseButtons.left


@pytest.fixture
def imgui_ctx():
    """A fresh ImGui context that writes no imgui.ini."""
    context = imgui.create_context()
    imgui.get_io().set_ini_filename(None)
    yield context
    imgui.destroy_context(context)


@pytest.fixture
def gui(gl_ctx, imgui_ctx):
    """Renderer, input bridge and a bound 320×240 RGBA8 framebuffer."""
    renderer = ImGuiRenderer(gl_ctx)
    fbo = gl_ctx.simple_framebuffer(SIZE)
    fbo.use()
    yield renderer, ImGuiInput(imgui.get_io(), Keys), fbo
    renderer.release()
    fbo.release()


def draw_frame(
    gui: tuple[ImGuiRenderer, ImGuiInput, moderngl.Framebuffer], body: Callable[[], None]
) -> np.ndarray:
    """Run one frame with ``body`` in a fixed window; return (240, 320, 4) uint8, row 0 on top."""
    renderer, gui_input, fbo = gui
    gui_input.prepare_frame(SIZE, SIZE, 1.0 / 60.0)
    imgui.new_frame()
    imgui.set_next_window_pos(WINDOW_POS)
    imgui.set_next_window_size(WINDOW_SIZE)
    imgui.begin("Panel")
    body()
    imgui.end()
    imgui.render()
    fbo.clear(*(c / 255.0 for c in CLEAR))
    renderer.render(imgui.get_draw_data())
    pixels = np.frombuffer(fbo.read(components=4), dtype=np.uint8)
    return pixels.reshape(SIZE[1], SIZE[0], 4)[::-1]


def item_rect() -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1) of the last item, in display pixels."""
    lo, hi = imgui.get_item_rect_min(), imgui.get_item_rect_max()
    return int(lo.x), int(lo.y), int(hi.x), int(hi.y)


def test_text_is_drawn_and_outside_stays_clear(gui):
    rects = {}

    def body():
        imgui.text("Hello envmap-studio")
        rects["text"] = item_rect()
        imgui.button("Press me")

    for _ in range(2):
        image = draw_frame(gui, body)

    x, y = WINDOW_POS
    w, h = WINDOW_SIZE
    outside = np.ones(image.shape[:2], dtype=bool)
    outside[y : y + h, x : x + w] = False
    assert np.all(image[outside] == CLEAR), "pixels outside the ImGui window changed"

    # Glyphs: a fair share of bright pixels, in separate strokes along the line.
    x0, y0, x1, y1 = rects["text"]
    lit = image[y0:y1, x0:x1, :3].min(axis=2) > 200
    assert 0.05 < lit.mean() < 0.6, lit.mean()
    columns = lit.any(axis=0)
    assert np.count_nonzero(columns[1:] != columns[:-1]) > 20, "text is not separate glyphs"

    # Solid fills sample the atlas's white pixel: the window body is exactly the
    # style colour blended over the clear colour.
    bg = imgui.get_style_color_vec4(imgui.Col_.window_bg)
    expected = np.array([bg.x, bg.y, bg.z]) * 255 * bg.w + np.array(CLEAR[:3]) * (1 - bg.w)
    body_pixel = image[y + h - 10, x + w // 2, :3].astype(float)
    assert np.all(np.abs(body_pixel - expected) <= 1.5), (body_pixel, expected)


@pytest.mark.parametrize("fmt", ["rgba32", "alpha8"])
def test_atlas_texels_reach_the_screen_unflipped(gui, fmt):
    """Show the atlas's top-left 128×32 texels 1:1 and compare with ImGui's CPU copy."""
    renderer, _, _ = gui
    fonts = imgui.get_io().fonts
    fonts.tex_desired_format = getattr(imgui.ImTextureFormat, fmt)
    shown = (128, 32)
    rects = {}

    def body():
        atlas = fonts.tex_data
        if atlas.tex_id:
            uv1 = (shown[0] / atlas.width, shown[1] / atlas.height)
            imgui.image(imgui.ImTextureRef(atlas.tex_id), shown, (0, 0), uv1)
            rects["image"] = item_rect()
        imgui.dummy((10, 10))
        rects["empty"] = item_rect()

    for _ in range(2):
        image = draw_frame(gui, body)

    atlas = fonts.tex_data
    assert renderer.texture(atlas.tex_id).components == (4 if fmt == "rgba32" else 1)
    texels = atlas.get_pixels_array().reshape(atlas.height, atlas.width, -1)[: shown[1], : shown[0]]
    if fmt == "alpha8":
        texels = np.concatenate([np.full((*texels.shape[:2], 3), 255, np.uint8), texels], axis=2)
    assert np.count_nonzero(texels[..., 3]) > 100, "the atlas corner holds no glyphs"
    x0, y0, x1, y1 = rects["image"]
    assert (x1 - x0, y1 - y0) == shown
    ex, ey = rects["empty"][:2]
    background = image[ey + 2, ex + 2, :3].astype(float)
    alpha = texels[..., 3:] / 255.0
    expected = texels[..., :3] * alpha + background * (1.0 - alpha)
    drawn = image[y0:y1, x0:x1, :3].astype(float)
    assert np.max(np.abs(drawn - expected)) <= 2.0


def test_press_and_release_in_one_frame_clicks(gui):
    _, gui_input, _ = gui
    clicks = []
    rects = {}

    def body():
        clicks.append(imgui.button("Press me"))
        rects["button"] = item_rect()

    draw_frame(gui, body)
    draw_frame(gui, body)
    x0, y0, x1, y1 = rects["button"]
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    gui_input.on_mouse_position_event(cx, cy, 0, 0)
    gui_input.on_mouse_press_event(cx, cy, LEFT_BUTTON)
    gui_input.on_mouse_release_event(cx, cy, LEFT_BUTTON)
    draw_frame(gui, body)
    draw_frame(gui, body)

    assert clicks[:2] == [False, False]
    assert True in clicks[2:], "the same-frame press and release were lost"
    assert clicks.count(True) == 1
    assert gui_input.want_capture_mouse


def test_keys_modifiers_and_text_reach_imgui(gui):
    _, gui_input, _ = gui
    values = []
    state = {"text": "", "focus": True}

    def body():
        if state["focus"]:
            imgui.set_keyboard_focus_here()
            state["focus"] = False
        _, state["text"] = imgui.input_text("##name", state["text"])
        values.append(state["text"])

    draw_frame(gui, body)
    no_mods = KeyModifiers()
    gui_input.on_key_event(Keys.LEFT_CTRL, Keys.ACTION_PRESS, no_mods)
    draw_frame(gui, body)
    assert imgui.get_io().key_ctrl, "Ctrl press with pre-event modifiers was not seen"
    gui_input.on_key_event(Keys.LEFT_CTRL, Keys.ACTION_RELEASE, no_mods)
    gui_input.on_unicode_char_entered("év")
    for _ in range(3):
        draw_frame(gui, body)
    assert not imgui.get_io().key_ctrl
    assert values[-1] == "év"
    assert gui_input.want_capture_keyboard

    gui_input.on_key_event(Keys.BACKSPACE, Keys.ACTION_PRESS, no_mods)
    gui_input.on_key_event(Keys.BACKSPACE, Keys.ACTION_RELEASE, no_mods)
    for _ in range(2):
        draw_frame(gui, body)
    assert values[-1] == "é"


def test_steady_frames_keep_one_font_texture_and_release_is_idempotent(gui):
    renderer, _, _ = gui
    for _ in range(4):
        draw_frame(gui, lambda: imgui.text("steady"))
    assert renderer.texture_creations == 1
    assert renderer.live_textures == 1
    renderer.release()
    renderer.release()
    assert renderer.live_textures == 0
    with pytest.raises(RuntimeError, match="release"):
        renderer.render(imgui.get_draw_data())


def test_new_glyphs_update_grow_and_destroy_textures(gui):
    renderer, _, _ = gui
    sizes = iter(range(20, 200, 12))
    while renderer.texture_creations < 2:
        size = next(sizes)

        def body(size=size):
            imgui.push_font(None, float(size))
            imgui.text("Grow 0123456789 ABCDEFGH")
            imgui.pop_font()

        draw_frame(gui, body)
    assert renderer.texture_updates > 0
    for _ in range(3):
        draw_frame(gui, lambda: imgui.text("settle"))
    assert renderer.texture_creations == 2
    assert renderer.live_textures == 1, "the outgrown atlas texture was not destroyed"

    (tex,) = [t for t in imgui.get_platform_io().textures if t.tex_id != 0]
    gpu = np.frombuffer(renderer.texture(tex.tex_id).read(), dtype=np.uint8)
    assert np.array_equal(gpu, tex.get_pixels_array()), "GPU atlas differs from ImGui's"


def test_gl_state_is_restored(gui, gl_ctx):
    gl_ctx.enable(moderngl.DEPTH_TEST | moderngl.CULL_FACE)
    gl_ctx.disable(moderngl.BLEND)
    gl_ctx.blend_func = moderngl.ONE, moderngl.ONE
    gl_ctx.blend_equation = moderngl.MAX
    gl_ctx.wireframe = True
    query = GLStateQuery(gl_ctx)
    for scissor in [(5, 5, 50, 50), None]:
        gl_ctx.viewport = (1, 2, 100, 100)
        gl_ctx.scissor = scissor
        before = query.capture()
        image = draw_frame(gui, lambda: imgui.text("state"))
        assert query.capture() == before
        assert before.scissor == scissor
    x, y = WINDOW_POS
    assert np.any(image[y + 100, x + 150] != CLEAR), "UI clipped by the caller's viewport"


def test_registered_texture_is_drawn_by_image(gui, gl_ctx):
    """An application texture in two windows: two draw lists share the buffers."""
    renderer, _, _ = gui
    red = gl_ctx.texture((4, 4), 4, data=bytes([255, 0, 0, 255] * 16))
    ref = renderer.register_texture(red)
    rects = {}

    def body():
        imgui.image(ref, (40, 40))
        rects["first"] = item_rect()
        imgui.set_next_window_pos((230, 150))
        imgui.set_next_window_size((80, 80))
        imgui.begin("Second")
        imgui.image(ref, (30, 30))
        rects["second"] = item_rect()
        imgui.end()

    for _ in range(2):
        image = draw_frame(gui, body)
    assert imgui.get_draw_data().cmd_lists_count == 2
    for x0, y0, x1, y1 in rects.values():
        assert np.all(image[y0 + 2 : y1 - 2, x0 + 2 : x1 - 2] == (255, 0, 0, 255))

    renderer.unregister_texture(red)
    with pytest.raises(KeyError, match="register_texture"):
        draw_frame(gui, body)
    red.release()


def test_every_character_of_the_methods_texts_has_a_glyph(imgui_ctx):
    """Titles, summaries, parameter help and units, every method's and the display's: no "�"
    (ImFont's lookup without fallback)."""
    from envstudio.engine.display import DISPLAY_PARAMETERS
    from envstudio.engine.registry import available_methods
    from envstudio.ui.style import load_ui_font

    font = load_ui_font()
    assert font is not None
    texts = [p.help + p.unit for p in DISPLAY_PARAMETERS]
    for cls in available_methods().values():
        texts += [cls.title, cls.summary, *(p.name + p.help + p.unit for p in cls.parameters)]
    characters = {c for text in texts for c in text if c.isprintable() and c != " "}
    assert {"λ", "⟨", "⟩", "∠", "∈", "−", "–"} <= characters  # the texts do use them
    missing = sorted(c for c in characters if not font.is_glyph_in_font(ord(c)))
    assert not missing, f"no glyph for {''.join(missing)!r}"


# -- docking (ui/docking.py): the 3D view is the dock space's central node -----------------

DOCK_DISPLAY = (1280, 800)


@pytest.fixture
def docked(gl_ctx, imgui_ctx):
    """Docking on, a renderer and a 1280x800 target: (renderer, input, layout, run_frame).

    ``run_frame(shown=True, events=())`` runs one frame (``events`` are calls on the input
    bridge, applied first) and returns (view rectangle, {panel: (rect, shown)})."""
    imgui.get_io().config_flags |= imgui.ConfigFlags_.docking_enable
    renderer = ImGuiRenderer(gl_ctx)
    fbo = gl_ctx.simple_framebuffer(DOCK_DISPLAY)
    fbo.use()
    gui_input = ImGuiInput(imgui.get_io(), Keys)
    layout = DockLayout()
    gui_input.prepare_frame(DOCK_DISPLAY, DOCK_DISPLAY, 1.0 / 60.0)
    imgui.new_frame()
    layout.warm_up()
    imgui.end_frame()

    def run_frame(shown: bool = True, events=()):
        for event in events:
            event(gui_input)
        gui_input.prepare_frame(DOCK_DISPLAY, DOCK_DISPLAY, 1.0 / 60.0)
        imgui.new_frame()
        view = layout.frame(shown)
        panels = {}
        if shown:
            for name in PANELS:
                imgui.begin(name, None, PANEL_FLAGS)
                imgui.text(name)
                pos, size = imgui.get_window_pos(), imgui.get_window_size()
                panels[name] = (ViewRect(pos.x, pos.y, size.x, size.y), imgui.is_window_docked())
                imgui.end()
        imgui.render()
        renderer.render(imgui.get_draw_data())
        return view, panels

    yield renderer, layout, run_frame
    renderer.release()
    fbo.release()


def assert_view_clear_of_panels(view: ViewRect, panels: dict) -> None:
    for name, (rect, is_docked) in panels.items():
        assert is_docked, f"{name} floats"
        assert not view.overlaps(rect), f"{name} {rect} covers the view {view}"


def test_the_default_layout_docks_every_panel_around_the_view(docked):
    _, _, run_frame = docked
    view, panels = run_frame()
    assert set(panels) == set(PANELS)
    assert_view_clear_of_panels(view, panels)
    method, stats = panels["Method"][0], panels["Stats"][0]
    assert 0 < view.x - (method.x + method.width) <= 4  # a splitter between them
    assert 0 < stats.x - (view.x + view.width) <= 4
    assert view.y > 0 and view.y + view.height == DOCK_DISPLAY[1]  # below the menu bar
    assert panels["Stats"][0] == panels["Capture"][0], "Stats and Capture share a tabbed node"
    assert view.width * view.height > 0.5 * DOCK_DISPLAY[0] * DOCK_DISPLAY[1]
    # hidden (Tab): the view is the whole display; shown again, the same layout
    hidden, _ = run_frame(shown=False)
    assert hidden == ViewRect(0.0, 0.0, *map(float, DOCK_DISPLAY))
    run_frame()  # the menu bar's work area moves a frame late
    assert run_frame()[0] == view


def test_a_dragged_splitter_moves_the_view_and_reset_layout_restores_it(docked, gl_ctx):
    _, layout, run_frame = docked
    default, panels = run_frame()
    method = panels["Method"][0]
    x, y = method.x + method.width + 1.0, method.y + 100.0
    steps = [
        lambda i: i.on_mouse_position_event(x, y, 0, 0),
        lambda i: i.on_mouse_press_event(x, y, LEFT_BUTTON),
        lambda i: i.on_mouse_drag_event(x + 150.0, y, 150, 0),
        lambda i: i.on_mouse_release_event(x + 150.0, y, LEFT_BUTTON),
    ]
    for step in steps:
        run_frame(events=[step])
    dragged, panels = run_frame()
    assert_view_clear_of_panels(dragged, panels)
    assert dragged.x == pytest.approx(default.x + 150.0, abs=2.0)
    assert dragged.x + dragged.width == default.x + default.width

    # the layout is ImGui's ini text (kept in the settings file): a new context restores it
    saved = imgui.save_ini_settings_to_memory()
    assert "[Docking][Data]" in saved and "CentralNode=1" in saved
    layout.reset()
    view, panels = run_frame()
    assert view == default
    assert_view_clear_of_panels(view, panels)
    assert panels["Stats"][1] and run_frame()[0] == default

    first = imgui.get_current_context()
    second = imgui.create_context()  # made current
    try:
        io = imgui.get_io()
        io.set_ini_filename(None)
        io.config_flags |= imgui.ConfigFlags_.docking_enable
        imgui.load_ini_settings_from_memory(saved)
        renderer = ImGuiRenderer(gl_ctx)
        ImGuiInput(io, Keys).prepare_frame(DOCK_DISPLAY, DOCK_DISPLAY, 1.0 / 60.0)
        restored = DockLayout()
        imgui.new_frame()
        restored.warm_up()
        imgui.end_frame()
        imgui.new_frame()
        assert restored.frame(True) == dragged
        imgui.end_frame()
        renderer.release()
    finally:
        imgui.destroy_context(second)
        imgui.set_current_context(first)


def test_the_view_rectangle_in_framebuffer_pixels():
    view = ViewRect(301.0, 21.0, 697.0, 779.0)
    assert gl_viewport(view, (1280, 800), (1280, 800)) == (301, 0, 697, 779)
    # HiDPI: two pixels a point; edges rounded, so neighbours still meet
    assert gl_viewport(view, (1280, 800), (2560, 1600)) == (602, 0, 1394, 1558)
    assert gl_viewport(ViewRect(0.25, 0.0, 10.5, 10.0), (20, 10), (40, 20)) == (0, 0, 22, 20)
    # clipped to the framebuffer, never negative
    assert gl_viewport(ViewRect(-5.0, -5.0, 50.0, 50.0), (20, 10), (20, 10)) == (0, 0, 20, 10)
    assert gl_viewport(ViewRect(30.0, 0.0, 5.0, 5.0), (20, 10), (20, 10))[2] == 0
