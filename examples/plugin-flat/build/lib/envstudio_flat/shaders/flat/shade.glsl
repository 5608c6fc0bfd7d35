// The key light of method `flat`: colour * (ambient + (1 - ambient) max(n.l, 0)).
const vec3 FLAT_LIGHT = vec3(0.48, 0.8, 0.36);  // unit length, from above and in front

vec3 flat_shade(vec3 colour, float ambient, vec3 n) {
    return colour * (ambient + (1.0 - ambient) * max(dot(n, FLAT_LIGHT), 0.0));
}
