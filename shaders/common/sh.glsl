// Order-2 real spherical harmonics, 9 coefficients; GLSL twin of
// app/envstudio/core/sh.py. Basis and order of seed 000 eq. 9 (DESIGN.md
// "Conventions"), for a unit direction (x, y, z):
//     Y0 = 1/sqrt(4pi);  Y1..Y3 = sqrt(3/4pi) (y, z, x);
//     Y4, Y5, Y7 = sqrt(15/4pi) (xy, yz, xz);  Y6 = sqrt(5/16pi) (3z^2 - 1);
//     Y8 = sqrt(15/16pi) (x^2 - y^2)
// Irradiance (seed 000 eq. 12 without kd / pi): E(n) = sum_i A_i L_i Y_i(n) with
// A = (pi, 2pi/3 x3, pi/4 x5); the diffuse radiance is kd / pi * E(n).

// Y_0 .. Y_8 at unit direction d.
void sh9_basis(vec3 d, out float y[9]) {
    y[0] = 0.28209479177387814;
    y[1] = 0.4886025119029199 * d.y;
    y[2] = 0.4886025119029199 * d.z;
    y[3] = 0.4886025119029199 * d.x;
    y[4] = 1.0925484305920792 * d.x * d.y;
    y[5] = 1.0925484305920792 * d.y * d.z;
    y[6] = 0.31539156525252005 * (3.0 * d.z * d.z - 1.0);
    y[7] = 1.0925484305920792 * d.x * d.z;
    y[8] = 0.5462742152960396 * (d.x * d.x - d.y * d.y);
}

// Irradiance E(n) for coefficients L_i (RGB) at unit normal n.
vec3 sh9_irradiance(vec3 coeffs[9], vec3 n) {
    const float A0 = 3.14159265358979;
    const float A1 = 2.0943951023931953;
    const float A2 = 0.7853981633974483;
    float y[9];
    sh9_basis(n, y);
    vec3 e = A0 * coeffs[0] * y[0];
    for (int i = 1; i < 4; ++i) {
        e += A1 * coeffs[i] * y[i];
    }
    for (int i = 4; i < 9; ++i) {
        e += A2 * coeffs[i] * y[i];
    }
    return e;
}
