"""The session protocol: what a method's hooks may use of a rendering session.

:class:`~envstudio.engine.method.Method` names it only under ``TYPE_CHECKING``,
so the method contract does not import the session that drives methods.
"""

from __future__ import annotations

from typing import Protocol

import moderngl
import numpy as np
import numpy.typing as npt

from envstudio.engine.frame import FrameRenderer, FrameStats
from envstudio.engine.method import Method
from envstudio.gpu.programs import ProgramLibrary
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.graph import Scene
from envstudio.shading.gpu_scene import GpuScene


class Session(Protocol):
    """What a method's hooks (report sections, figures, bench tables) may use of a session.

    :class:`envstudio.engine.session.RenderSession` is the one implementation:
    a scene on the GPU, its camera, the frame renderer and the methods' instances.
    """

    ctx: moderngl.Context
    programs: ProgramLibrary
    gpu_scene: GpuScene
    renderer: FrameRenderer
    camera: OrbitCamera

    @property
    def scene(self) -> Scene: ...

    def method(self, name: str) -> Method: ...

    def apply(self, method: Method, assignments: list[str]) -> None: ...

    def render_offscreen(self, method: str | Method, size: tuple[int, int]) -> FrameStats: ...

    def read_ldr(self) -> npt.NDArray[np.uint8]: ...

    def read_hdr(self) -> npt.NDArray[np.float32]: ...
