// Schlick's Fresnel approximation, seed 000 section 5.2:
// F = f_lambda + (1 - f_lambda) (1 - cos theta)^5, one parameter f_lambda, or one per RGB
// channel (f_lambda "the color of reflected white light at normal incidence").
float schlick_fresnel(float f_lambda, float cos_theta) {
    float m = 1.0 - clamp(cos_theta, 0.0, 1.0);
    float m2 = m * m;
    return f_lambda + (1.0 - f_lambda) * m2 * m2 * m;
}

vec3 schlick_fresnel(vec3 f_lambda, float cos_theta) {
    float m = 1.0 - clamp(cos_theta, 0.0, 1.0);
    float m2 = m * m;
    return f_lambda + (1.0 - f_lambda) * m2 * m2 * m;
}
