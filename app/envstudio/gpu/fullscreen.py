"""Full-screen passes: one triangle generated from ``gl_VertexID``, no buffers."""

from __future__ import annotations

import moderngl


class FullscreenPass:
    """Draws one full-screen triangle with a given program.

    The program's vertex stage must include ``common/fullscreen_vs.glsl`` (or
    otherwise derive its position from ``gl_VertexID``). One empty vertex array
    is kept per program.
    """

    def __init__(self, ctx: moderngl.Context):
        self.ctx = ctx
        self._vaos: dict[int, moderngl.VertexArray] = {}

    def draw(self, program: moderngl.Program) -> None:
        """Draw the triangle into the currently bound framebuffer."""
        vao = self._vaos.get(program.glo)
        if vao is None:
            vao = self.ctx.vertex_array(program, [])
            self._vaos[program.glo] = vao
        vao.render(moderngl.TRIANGLES, vertices=3)

    def release(self) -> None:
        """Release the vertex arrays; safe to call twice."""
        for vao in self._vaos.values():
            vao.release()
        self._vaos.clear()
