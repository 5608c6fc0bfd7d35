// PEM texgen (seed 003 section 4, run-time): where a reflected ray meets the EM
// geometry. GLSL twin of BoxGeometry.exit_distance and
// EllipsoidGeometry.exit_distance in app/envstudio/bake/pem/infer.py; a ray that
// misses returns -1. The lookup vector is origin + t d minus the EM origin.

const float PEM_MISS = -1.0;

// Exit parameter t >= 0 of the ray o + t d from the axis-aligned box [lo, hi]
// (slab method; a direction parallel to a face's slab leaves through the others).
float pem_box_exit(vec3 o, vec3 d, vec3 lo, vec3 hi) {
    float far = 1e30;
    float near = -1e30;
    for (int k = 0; k < 3; ++k) {
        if (abs(d[k]) < 1e-20) {
            if (o[k] < lo[k] || o[k] > hi[k]) {
                return PEM_MISS;
            }
            continue;
        }
        float t1 = (lo[k] - o[k]) / d[k];
        float t2 = (hi[k] - o[k]) / d[k];
        far = min(far, max(t1, t2));
        near = max(near, min(t1, t2));
    }
    return far >= max(near, 0.0) ? far : PEM_MISS;
}

// Larger root t >= 0 of the ray o + t d with the ellipsoid sum(((x - c) / r)^2) = 1.
float pem_ellipsoid_exit(vec3 o, vec3 d, vec3 centre, vec3 radii) {
    vec3 oo = (o - centre) / radii;
    vec3 dd = d / radii;
    float a = dot(dd, dd);
    float b = dot(oo, dd);
    float c = dot(oo, oo) - 1.0;
    float disc = b * b - a * c;
    if (disc < 0.0) {
        return PEM_MISS;
    }
    float t = (-b + sqrt(disc)) / a;
    return t >= 0.0 ? t : PEM_MISS;
}

// Lookup vector of a geometry hit (exit point minus the EM origin); the ray
// direction where the ray missed (the geometry then acts as a sphere at infinity).
vec3 pem_lookup(vec3 o, vec3 d, float t, vec3 em_origin) {
    vec3 q = o + t * d - em_origin;
    return (t < 0.0 || dot(q, q) == 0.0) ? d : q;
}
