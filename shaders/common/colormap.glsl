// Perceptual colour ramp for error heat maps: a piecewise-linear fit of
// matplotlib's "magma" through 6 stops (black -> purple -> red -> yellow-white).
// Python twin: app/envstudio/core/colormap.py (MAGMA_STOPS).
vec3 colormap_magma(float t) {
    const vec3 stops[6] = vec3[6](
        vec3(0.001, 0.000, 0.014), vec3(0.231, 0.059, 0.439), vec3(0.550, 0.161, 0.506),
        vec3(0.868, 0.288, 0.409), vec3(0.994, 0.624, 0.427), vec3(0.987, 0.991, 0.750));
    float x = clamp(t, 0.0, 1.0) * 5.0;
    int i = min(int(x), 4);
    return mix(stops[i], stops[i + 1], x - float(i));
}
