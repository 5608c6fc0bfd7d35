// The reflector's material for the reference (methods/reference.py): its
// uniforms and one-sample BRDF sampling, used wherever a path continues at a
// reflector (paths.glsl). Needs common/fresnel.glsl and common/sampling.glsl.
//   model 0 (seed 000 eq. 8): (1 - F) k_d / pi (n.l) + F (N+1)/2pi (r.l)^N, F = Schlick(n.v);
//   model 1 (microfacet): k_d / pi (1 - F(n.v)) (n.l) + GGX D G2 F(v.h) / (4 n.v);
//   model 2 (banks): a traced path that meets a reflector again ends there (black):
//   the tracer does not carry the tangent field; compare banks with trace=false.
// k_d and f_lambda are linear RGB: F is Schlick's per channel, and so is every weight.
uniform int u_brdf_model;
uniform vec3 u_kd;
uniform vec3 u_fresnel;
uniform float u_phong_exponent;

// Beyond this Phong exponent the lobe is narrower than any environment texel
// (half-width under 0.3 degrees): a continuing path takes the mirror direction.
const float MIRROR_EXPONENT = 1e5;

// GGX roughness of a Phong exponent N (a Phong exponent N is about a Blinn exponent 4N).
float microfacet_alpha() { return sqrt(2.0 / (4.0 * u_phong_exponent + 2.0)); }

// The mean of an RGB weight: what a choice between lobes is made in proportion to.
float channel_mean(vec3 c) { return (c.r + c.g + c.b) / 3.0; }

// The reflector's response at a hit reached along `direction` (unit normal n facing the
// arrival) for the direction l: f (n.l) per RGB channel (model 0: (1 - F) k_d / pi (n.l) +
// F (N+1)/2pi (r.l)^N, eq. 8 without ⟨n, l⟩ on the Phong lobe; model 1: the GGX lobe plus the
// diffuse one), and `pdf`, the density in solid angle sample_reflector draws l with: the
// mixture of the lobes' densities, each picked in proportion to the mean over the channels
// of its albedo. Zero for model 2 and below the surface.
vec3 reflector_response(vec3 direction, vec3 n, vec3 l, out float pdf) {
    pdf = 0.0;
    float n_dot_l = dot(n, l);
    if (u_brdf_model == 2 || n_dot_l <= 0.0) return vec3(0.0);
    vec3 v = -direction;
    float n_dot_v = max(dot(n, v), 1e-4);
    vec3 F = schlick_fresnel(u_fresnel, n_dot_v);
    vec3 diffuse = (1.0 - F) * u_kd;
    float diffuse_mean = channel_mean(diffuse);
    float specular_mean = channel_mean(F);
    if (diffuse_mean + specular_mean <= 0.0) return vec3(0.0);
    float p_diffuse = diffuse_mean / (diffuse_mean + specular_mean);
    if (u_brdf_model == 0) {
        float lobe = phong_lobe(reflect(direction, n), l, u_phong_exponent);
        pdf = p_diffuse * n_dot_l / PI + (1.0 - p_diffuse) * lobe;
        return diffuse * n_dot_l / PI + F * lobe;
    }
    float alpha = microfacet_alpha();
    vec3 h = normalize(l + v);
    float n_dot_h = max(dot(n, h), 0.0);
    float v_dot_h = max(dot(v, h), 1e-4);
    float D = ggx_d(n_dot_h, alpha);
    vec3 specular = D * ggx_g2(n_dot_l, n_dot_v, alpha) * schlick_fresnel(u_fresnel, v_dot_h)
                    / (4.0 * n_dot_v);
    pdf = p_diffuse * n_dot_l / PI + (1.0 - p_diffuse) * D * n_dot_h / (4.0 * v_dot_h);
    return specular + diffuse / PI * n_dot_l;
}

// Continue a path that arrived along `direction` at a reflector with unit normal n (facing
// the arrival): a new direction drawn from the mixture of the material's lobes, a lobe
// picked in proportion to the mean over the channels of its albedo ((1 - F) k_d or F) and
// drawn exactly, with `weight` = f (n.l) / pdf per RGB channel and `pdf` the mixture's
// density (reflector_response). A Phong lobe narrower than MIRROR_EXPONENT takes the mirror
// direction with weight F and pdf 0 (a delta: no other technique can draw it). Model 2
// continues nowhere (weight 0). xi: three numbers in [0, 1).
vec3 sample_reflector(vec3 direction, vec3 n, vec3 xi, out vec3 weight, out float pdf) {
    weight = vec3(0.0);
    pdf = 0.0;
    if (u_brdf_model == 2) return n;
    vec3 v = -direction;
    vec3 F = schlick_fresnel(u_fresnel, max(dot(n, v), 1e-4));
    float diffuse_mean = channel_mean((1.0 - F) * u_kd);
    float specular_mean = channel_mean(F);
    if (diffuse_mean + specular_mean <= 0.0) return n;
    float p_diffuse = diffuse_mean / (diffuse_mean + specular_mean);
    vec3 l;
    if (xi.z < p_diffuse) {
        l = sample_cosine(n, xi.xy);
    } else if (u_brdf_model == 0) {
        vec3 r = reflect(direction, n);
        if (u_phong_exponent >= MIRROR_EXPONENT) {
            weight = F / (1.0 - p_diffuse);
            return r;
        }
        l = sample_phong(r, u_phong_exponent, xi.xy);
    } else {
        l = reflect(direction, sample_ggx_half(n, microfacet_alpha(), xi.xy));
    }
    vec3 f = reflector_response(direction, n, l, pdf);
    weight = pdf > 0.0 ? f / pdf : vec3(0.0);
    return l;
}
