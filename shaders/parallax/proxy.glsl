// The proxy volume of a parallax-corrected cube map (Lagarde and Zanuttini, "Local
// image-based lighting with parallax-corrected cubemaps", SIGGRAPH 2012 talk): a
// reflection ray from the shaded point p along the unit vector r is intersected with
// the box or sphere the scene declares, and the cube map captured at the probe is
// looked up towards the hit. The Python twin is scene/proxy.py.
// Defines: PROXY (0: none, the lookup along r; 1: box; 2: sphere).
#if PROXY == 1
uniform vec3 u_box_min;
uniform vec3 u_box_max;
#elif PROXY == 2
uniform vec3 u_sphere_centre;
uniform float u_sphere_radius;
#endif

// t > 0 at which p + t r leaves the proxy; 0 where there is no exit ahead (p outside,
// or no proxy): the caller then looks up along r, uncorrected.
float proxy_exit(vec3 p, vec3 r) {
#if PROXY == 1
    // Each axis' slab plane ahead of the ray; the nearest of the three is the exit.
    vec3 safe = vec3(r.x != 0.0 ? r.x : 1e-30, r.y != 0.0 ? r.y : 1e-30,
                     r.z != 0.0 ? r.z : 1e-30);
    vec3 bound = mix(u_box_min, u_box_max, step(0.0, safe));
    vec3 t = (bound - p) / safe;
    return max(min(t.x, min(t.y, t.z)), 0.0);
#elif PROXY == 2
    // The larger root of |p + t r - c|^2 = R^2.
    vec3 o = p - u_sphere_centre;
    float b = dot(o, r);
    float k = dot(o, o) - u_sphere_radius * u_sphere_radius;
    float disc = b * b - k;
    return disc > 0.0 ? max(-b + sqrt(disc), 0.0) : 0.0;
#else
    return 0.0;
#endif
}
