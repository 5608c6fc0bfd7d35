#version 330 core
// Method `banks`, seed 004 section 5.3: the reflector with the anisotropic 3D map
// L_banks(t, <v,t>) (methods/banks/maps.py), combined with a diffuse term by
// seed 000 eq. 8,
//   L_o = (1 - F(r.n)) L_diffuse + F(r.n) L_banks(t, <v,t>),
// with Schlick's F (seed 000 section 5.2) and mirror's diffuse term from the static
// cube map (common/eq8.glsl). "Compute the 3D texture coordinates at every vertex"
// (section 5.3): per vertex (u_per_pixel false) the tangent t, orthogonalised
// against the vertex normal, and <v,t> are computed in the vertex stage and
// interpolated; the fragment folds them and maps them to (u, v, w). Interpolating
// (u, v, w) themselves would smear the whole face into a triangle whose vertices
// fold to opposite sides of the hemisphere. Per pixel, t and <v,t> come from the
// interpolated tangent, normal and position.
#include "common/paraboloid.glsl"
#include "banks/lookup.glsl"
#include "common/banks_brdf.glsl"
#if defined VERTEX_SHADER
#include "common/mesh_world.glsl"
#include "common/mesh_tangent.glsl"
uniform mat4 u_view;
uniform mat4 u_projection;
uniform vec3 u_camera_position;
out vec4 v_vertex_tangent;  // xyz: t, w: <v,t> at the vertex

void main() {
    vec4 world = mesh_world();
    mesh_tangent();
    vec3 n = normalize(v_world_normal);
    vec3 t = banks_tangent(v_world_tangent, n);
    vec3 v = normalize(u_camera_position - world.xyz);
    v_vertex_tangent = vec4(t, dot(v, t));
    gl_Position = u_projection * u_view * world;
}
#elif defined FRAGMENT_SHADER
#include "common/fresnel.glsl"
#include "common/eq8.glsl"
uniform sampler3D u_map;
uniform samplerCube u_diffuse_map;
uniform float u_map_size;
uniform bool u_per_pixel;
uniform bool u_normalise;
in vec3 v_world_tangent;
in vec4 v_vertex_tangent;
out vec4 f_color;

void main() {
    vec3 n, r;
    reflection_frame(v_world_normal, v_world_position, u_camera_position, n, r);
    vec3 t;
    float b;
    if (u_per_pixel) {
        t = banks_tangent(v_world_tangent, n);
        b = dot(normalize(u_camera_position - v_world_position), t);
    } else {
        float len = length(v_vertex_tangent.xyz);
        t = len > 1e-6 ? v_vertex_tangent.xyz / len : banks_tangent(vec3(0.0), n);
        b = clamp(v_vertex_tangent.w, -1.0, 1.0);
    }
    vec3 glossy = banks_glossy(u_map, banks_coordinates(t, b, u_map_size), u_normalise);
    f_color = vec4(eq8_shade(n, r, texture(u_diffuse_map, n).rgb, glossy, u_kd, u_fresnel), 1.0);
}
#endif
