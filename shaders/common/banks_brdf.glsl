// The Banks BRDF of seed 004 section 5.3 (GLSL twin of methods/banks/lobe.py), shared by
// method `banks` and the reference's model=banks:
//   f = max(0, sqrt(1 - <l,t>^2) sqrt(1 - <v,t>^2) - <l,t><v,t> - s) / (1 - s)^2.
uniform float u_sharpness;

// Unit tangent orthogonal to unit n from an interpolated tangent; a degenerate one
// (parallel to n, or zero) becomes n x e for the axis e least aligned with n.
vec3 banks_tangent(vec3 tangent, vec3 n) {
    vec3 t = tangent - dot(tangent, n) * n;
    float len = length(t);
    if (len > 1e-6 * max(length(tangent), 1e-30)) return t / len;
    vec3 a = abs(n);
    vec3 e = a.x <= a.y && a.x <= a.z ? vec3(1.0, 0.0, 0.0)
             : (a.y <= a.z ? vec3(0.0, 1.0, 0.0) : vec3(0.0, 0.0, 1.0));
    return normalize(cross(n, e));
}

float banks_lobe(float l_dot_t, float v_dot_t) {
    float s = u_sharpness;
    float bracket = sqrt(max(1.0 - l_dot_t * l_dot_t, 0.0)) * sqrt(max(1.0 - v_dot_t * v_dot_t, 0.0))
                    - l_dot_t * v_dot_t - s;
    return max(bracket, 0.0) / ((1.0 - s) * (1.0 - s));
}

// The lobe's support in theta = angle(l, t): |theta - psi| < acos(s), psi = pi - angle(v, t).
void banks_band(float v_dot_t, out float theta0, out float theta1, out float psi) {
    const float pi = 3.14159265358979;
    psi = pi - acos(clamp(v_dot_t, -1.0, 1.0));
    float w = acos(u_sharpness);
    theta0 = max(0.0, psi - w);
    theta1 = min(pi, psi + w);
}

// Integral of the lobe over the sphere (methods/banks/lobe.py lobe_integral, closed form).
float banks_integral(float v_dot_t) {
    float theta0, theta1, psi;
    banks_band(v_dot_t, theta0, theta1, psi);
    float s = u_sharpness;
    float hi = -0.25 * cos(2.0 * theta1 - psi) + 0.5 * theta1 * sin(psi) + s * cos(theta1);
    float lo = -0.25 * cos(2.0 * theta0 - psi) + 0.5 * theta0 * sin(psi) + s * cos(theta0);
    return 2.0 * 3.14159265358979 * (hi - lo) / ((1.0 - s) * (1.0 - s));
}
