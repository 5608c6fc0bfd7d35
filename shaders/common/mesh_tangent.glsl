// The world-space tangent of anisotropic materials (methods/banks/tangent_buffers.py):
// include after common/mesh_world.glsl in a VERTEX_SHADER section. A tangent is a
// direction on the surface, so it is transformed by the model matrix itself (not
// the normal matrix); the fragment stage orthogonalises it against the normal.
in vec3 in_tangent;
out vec3 v_world_tangent;

void mesh_tangent() { v_world_tangent = mat3(u_model) * in_tangent; }
