// Standard mesh vertex stage: world position and normal for per-pixel shading.
// Include in a VERTEX_SHADER section; defines main().
uniform mat4 u_model;
uniform mat3 u_normal_matrix;
uniform mat4 u_view;
uniform mat4 u_projection;

in vec3 in_position;
in vec3 in_normal;

out vec3 v_world_position;
out vec3 v_world_normal;

void main() {
    vec4 world = u_model * vec4(in_position, 1.0);
    v_world_position = world.xyz;
    v_world_normal = u_normal_matrix * in_normal;
    gl_Position = u_projection * u_view * world;
}
