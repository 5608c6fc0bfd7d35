#version 330 core
// Method `pem`: playback of parameterized environment maps (seed 003 section 4).
// Per fragment of a reflector part: the reflected ray off the interpolated
// surface point and normal (texgen, seed 003 section 4 "run-time", done per
// fragment rather than per vertex), intersected with the distant box and with the
// part's local ellipsoid; the hit points minus the part's EM origin look up the
// baked cube maps of the nearest views (trilinear, common to the bake's rendering
// matrix: atlas.glsl). Composite (seed 003 section 4, "Layered EMs"):
//     I = alpha_L L + (1 - alpha_L) D     (local premultiplied: L_p = alpha_L L)
//     C = (1 - F) k_d / pi E_sh9(n) + F I
// with Schlick's F (seed 000 section 5.2) as the bake traced it, blended over
// the views with weights u_view_weight. Convex-hull triangles (gl_PrimitiveID
// flags) use the distant map only. Models: 0 layered box + ellipsoid, 1 a single
// sphere at infinity per view (lookup = r), 2 the static EM (u_static, seed 003
// Figure 1c), 3 the PTM (seed 003 section 6, Figure 7; issue 31): a surface
// texture looked up by the surface point minus the EM origin (nothing reflected),
// its per-view maps summed with the weights of a per-texel polynomial in the
// view parameters (methods/pem/blending.py ptm_blend: up to 16 views, weights
// of either sign), chosen by u_em_model.
//
// PEM_LOOKUP: instead of shading, write what the bake builds its rendering
// matrix from: per model (face, s, t, lod) and (part, hull, triangle, 1); the
// PTM's lookup in a fifth target.
//
// PEM_TEXGEN_VERTEX: the paper's texgen, per vertex (the reflected ray off each
// vertex with its normal, intersected in the vertex stage), the lookup vectors
// interpolated across triangles; the level still comes from their derivatives.
uniform vec3 u_camera_position;
uniform vec3 u_box_lo;
uniform vec3 u_box_hi;
uniform vec3 u_em_origin;
uniform vec3 u_ellipsoid_centre;
uniform vec3 u_ellipsoid_radii;
#include "common/reflection.glsl"
#include "pem/texgen.glsl"

#if defined VERTEX_SHADER
#include "common/mesh_world.glsl"
uniform mat4 u_view;
uniform mat4 u_projection;
out vec3 v_q_distant;
out vec3 v_q_local;
out vec3 v_reflected;

void main() {
    vec4 world = mesh_world();
    gl_Position = u_projection * u_view * world;
#if defined PEM_TEXGEN_VERTEX
    vec3 n, r;
    reflection_frame(v_world_normal, world.xyz, u_camera_position, n, r);
    vec3 p = world.xyz;
    v_q_distant = pem_lookup(p, r, pem_box_exit(p, r, u_box_lo, u_box_hi), u_em_origin);
    v_q_local = pem_lookup(
        p, r, pem_ellipsoid_exit(p, r, u_ellipsoid_centre, u_ellipsoid_radii), u_em_origin);
    v_reflected = r;
#else
    v_q_distant = vec3(0.0);
    v_q_local = vec3(0.0);
    v_reflected = vec3(0.0);
#endif
}
#elif defined FRAGMENT_SHADER
#include "common/cubemap.glsl"
#include "common/fresnel.glsl"
#include "common/sh.glsl"
#include "pem/atlas.glsl"

in vec3 v_q_distant;
in vec3 v_q_local;
in vec3 v_reflected;
uniform int u_part;
uniform int u_parts;
uniform usampler2D u_hull;   // one flag per triangle, row-major in u_hull_width columns
uniform int u_hull_width;
uniform int u_hull_offset;   // this part's first triangle in u_hull
uniform bool u_use_hull;
in vec3 v_world_position;
in vec3 v_world_normal;

#if defined PEM_LOOKUP
layout(location = 0) out vec4 f_distant;
layout(location = 1) out vec4 f_local;
layout(location = 2) out vec4 f_sphere;
layout(location = 3) out vec4 f_part;
layout(location = 4) out vec4 f_ptm;
#else
uniform sampler2D u_distant;
uniform sampler2D u_local;
uniform sampler2D u_sphere;
uniform sampler2D u_ptm;
uniform samplerCube u_static;
uniform int u_em_model;
uniform int u_view_map[16];    // view index of each blended sample
uniform float u_view_weight[16];
uniform int u_views_blended;   // 1 (unblended), 2 (arc), 4 (grid), up to 16 (PTM)
uniform bool u_use_distant;
uniform bool u_use_local;
uniform bool u_use_fresnel;
uniform bool u_use_diffuse;
uniform vec3 u_fresnel;  // f_lambda per RGB channel
uniform vec3 u_kd;
uniform float u_lod_bias;      // the bake's parameters["lod_bias"] (+ the lod_scale offset)
uniform vec3 u_sh9[9];
out vec4 f_color;
#endif

bool pem_on_hull() {
    int index = u_hull_offset + gl_PrimitiveID;
    return texelFetch(u_hull, ivec2(index % u_hull_width, index / u_hull_width), 0).r != 0u;
}

void main() {
    vec3 n, r;
    reflection_frame(v_world_normal, v_world_position, u_camera_position, n, r);
#if defined PEM_TEXGEN_VERTEX
    vec3 q_distant = v_q_distant;
    vec3 q_local = v_q_local;
    vec3 r_lookup = v_reflected;
#else
    vec3 p = v_world_position;
    vec3 q_distant = pem_lookup(p, r, pem_box_exit(p, r, u_box_lo, u_box_hi), u_em_origin);
    vec3 q_local = pem_lookup(
        p, r, pem_ellipsoid_exit(p, r, u_ellipsoid_centre, u_ellipsoid_radii), u_em_origin);
    vec3 r_lookup = r;
#endif
    // the PTM's surface texture: the point itself (linear, so the same per vertex)
    vec3 q_ptm = v_world_position - u_em_origin;
    // derivatives in uniform control flow, before any branch
    float lod_distant = pem_lod(q_distant);
    float lod_local = pem_lod(q_local);
    float lod_sphere = pem_lod(r_lookup);
    float lod_ptm = pem_lod(q_ptm);
    bool hull = u_use_hull && pem_on_hull();
    int face_distant, face_local, face_sphere;
    vec2 st_distant = cube_face_uv(q_distant, face_distant);
    vec2 st_local = cube_face_uv(q_local, face_local);
    vec2 st_sphere = cube_face_uv(r_lookup, face_sphere);
    int face_ptm;
    vec2 st_ptm = cube_face_uv(q_ptm, face_ptm);
#if defined PEM_LOOKUP
    f_distant = vec4(float(face_distant), st_distant, lod_distant);
    f_local = vec4(float(face_local), st_local, lod_local);
    f_sphere = vec4(float(face_sphere), st_sphere, lod_sphere);
    f_part = vec4(float(u_part), hull ? 1.0 : 0.0, float(gl_PrimitiveID), 1.0);
    f_ptm = vec4(float(face_ptm), st_ptm, lod_ptm);
#else
    vec3 incident = vec3(0.0);
    if (u_em_model == 2) {
        incident = texture(u_static, r).rgb;
    } else {
        for (int k = 0; k < u_views_blended; ++k) {
            int map = u_view_map[k] * u_parts + u_part;
            vec3 sample_k;
            if (u_em_model == 1) {
                sample_k = pem_trilinear(
                    u_sphere, map, face_sphere, st_sphere, lod_sphere + u_lod_bias).rgb;
            } else if (u_em_model == 3) {
                sample_k = pem_trilinear(u_ptm, map, face_ptm, st_ptm, lod_ptm + u_lod_bias).rgb;
            } else {
                vec3 distant = u_use_distant
                    ? pem_trilinear(
                        u_distant, map, face_distant, st_distant, lod_distant + u_lod_bias).rgb
                    : vec3(0.0);
                vec4 local = (u_use_local && !hull)
                    ? pem_trilinear(u_local, map, face_local, st_local, lod_local + u_lod_bias)
                    : vec4(0.0);
                sample_k = local.rgb + (1.0 - local.a) * distant;
            }
            incident += u_view_weight[k] * sample_k;
        }
    }
    // the diffuse layer (1 - F) d and the Fresnel modulation layer F (Figure 4);
    // the Fresnel switch drops the modulation only
    vec3 fresnel = schlick_fresnel(u_fresnel, dot(r, n));
    vec3 diffuse = u_use_diffuse
        ? (1.0 - fresnel) * u_kd / 3.14159265358979 * max(sh9_irradiance(u_sh9, n), vec3(0.0))
        : vec3(0.0);
    f_color = vec4(diffuse + (u_use_fresnel ? fresnel : vec3(1.0)) * incident, 1.0);
#endif
}
#endif
