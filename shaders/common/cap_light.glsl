// Irradiance of a uniform spherical cap light; GLSL twin of
// app/envstudio/core/sh_lights.py cap_irradiance (Snyder 1996, the closed form for
// a sphere light). Returns E / |V|, with |V| = pi L sin^2(alpha) the cap's moment:
// max(cos theta, 0) while the cap is wholly above or below the horizon, and the
// exact clipped integral while it straddles it.
float cap_irradiance(float cos_theta, float sin2_alpha) {
    const float PI = 3.14159265358979;
    float c = clamp(cos_theta, -1.0, 1.0);
    if (c * c >= sin2_alpha || sin2_alpha < 1e-6) {
        return max(c, 0.0);
    }
    float sin_theta = sqrt(max(1.0 - c * c, 1e-12));
    float x = sqrt(1.0 / sin2_alpha - 1.0);
    float y = clamp(-x * c / sin_theta, -1.0, 1.0);
    float root = sin_theta * sqrt(1.0 - y * y);
    float e = (c * acos(y) - x * root) * sin2_alpha + atan(root / x);
    return max(e, 0.0) / (PI * sin2_alpha);
}
