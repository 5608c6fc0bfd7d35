// Lat-long (equirectangular) parameterization; GLSL twin of
// app/envstudio/core/latlong.py. Convention (DESIGN.md "Conventions"), world
// space right-handed with +Y up:
//     u = 0.5 + atan(x, -z) / 2pi        v = acos(y) / pi
// v = 0 is +Y and image row 0; uploaded row 0 first, the texture coordinate
// is (s, t) = (u, v). The centre (0.5, 0.5) looks down -Z; u = 0.75 is +X.
// Sample with REPEAT in s and CLAMP_TO_EDGE in t.

const float LATLONG_PI = 3.14159265358979;

// Texture coordinates of direction d (any length but zero); u = 0.5 on the poles.
// acos(y) is taken as atan(|xz|, y), which keeps float precision near the poles.
vec2 latlong_uv(vec3 d) {
    float u = (d.x == 0.0 && d.z == 0.0) ? 0.5 : 0.5 + atan(d.x, -d.z) / (2.0 * LATLONG_PI);
    return vec2(u, atan(length(d.xz), d.y) / LATLONG_PI);
}

// Unit direction of texture coordinates uv: phi = 2pi (u - 0.5), theta = pi v,
// d = (sin theta sin phi, cos theta, -sin theta cos phi).
vec3 latlong_direction(vec2 uv) {
    float phi = 2.0 * LATLONG_PI * (uv.x - 0.5);
    float theta = LATLONG_PI * uv.y;
    return vec3(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
}

// Exact solid angle (sr) of texel (column, row) of a size = (w, h) map: the band
// integral (2pi / w)(cos theta0 - cos theta1), written as a product of sines so
// it keeps its precision near the poles.
float latlong_texel_solid_angle(ivec2 texel, ivec2 size) {
    float dtheta = LATLONG_PI / float(size.y);
    float theta_mid = (float(texel.y) + 0.5) * dtheta;
    return (2.0 * LATLONG_PI / float(size.x)) * 2.0 * sin(theta_mid) * sin(0.5 * dtheta);
}
