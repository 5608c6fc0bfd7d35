"""Method ``flat``: every reflector in one colour, lit by a fixed key light (no environment)."""

from envstudio.plugin import FrameInputs, Method, Parameter, set_uniform


class FlatMethod(Method):
    """The reflector shaded ``colour`` · (ambient + (1 − ambient) max(n·l, 0)).

    An environment-map technique would look the environment up here; this one
    shows the contract alone: declared parameters, a program loaded from the
    plugin's own shader folder, one timed pass over the scene's reflectors.
    """

    name = "flat"
    title = "Flat colour (plugin example)"
    summary = "The reflector in one declared colour, lit by a fixed key light."
    parameters = (
        Parameter("colour", "color", (0.8, 0.3, 0.1), 0.0, 1.0, "", "Linear RGB of the surface."),
        Parameter("ambient", "float", 0.25, 0.0, 1.0, "", "Share of the colour without light."),
    )

    def render(self, frame: FrameInputs) -> None:
        frame.target.use()
        program = self.programs.get("flat/flat.glsl")
        set_uniform(program, "u_colour", tuple(self.values["colour"]))
        set_uniform(program, "u_ambient", float(self.values["ambient"]))
        with frame.timer.measure("flat"):
            frame.draw_reflectors(program)  # u_view, u_projection, u_model, u_normal_matrix
