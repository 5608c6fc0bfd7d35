// The 3D map of method `banks` (seed 004 section 5.3; layout in methods/banks/lobe.py and
// methods/banks/maps.py): texture coordinates of (t, <v,t>) and the glossy radiance there.
// Include after common/paraboloid.glsl.
const float BANKS_BORDER = 2.0;  // methods/banks/lobe.py BORDER
const float BANKS_PI = 3.14159265358979;

// (u, v, w) of unit tangent t and b = <v,t>: folded onto t_z >= 0 by the symmetry
// (t, b) -> (-t, -b), the front paraboloid face with its border, w = acos(b) / pi.
vec3 banks_coordinates(vec3 t, float b, float size) {
    if (t.z < 0.0) {
        t = -t;
        b = -b;
    }
    int face;
    vec2 uv = paraboloid_uv(t, size, BANKS_BORDER, face);
    return vec3(uv, acos(clamp(b, -1.0, 1.0)) / BANKS_PI);
}

// The map's glossy radiance at (u, v, w): the paper's L_banks, or with `normalise`
// divided by the map of a unit environment (alpha), so the lobe integrates to 1.
vec3 banks_glossy(sampler3D map, vec3 coordinates, bool normalise) {
    vec4 m = texture(map, coordinates);
    return normalise ? m.rgb / max(m.a, 1e-30) : m.rgb;
}
