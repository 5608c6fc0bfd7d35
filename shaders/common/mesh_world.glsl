// Model to world for mesh vertex stages: the attributes, the model and normal
// matrices and the world-space varyings. Include in a VERTEX_SHADER section.
uniform mat4 u_model;
uniform mat3 u_normal_matrix;

in vec3 in_position;
in vec3 in_normal;

out vec3 v_world_position;
out vec3 v_world_normal;

// Sets v_world_position and v_world_normal; returns the world position (w = 1).
vec4 mesh_world() {
    vec4 world = u_model * vec4(in_position, 1.0);
    v_world_position = world.xyz;
    v_world_normal = u_normal_matrix * in_normal;
    return world;
}
