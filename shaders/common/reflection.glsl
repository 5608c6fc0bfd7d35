// The reflection frame of a surface point, for any stage: the unit normal n
// (turned towards the viewer: back faces of open meshes reflect too) and the
// mirror reflection r of the view direction, both in world space.
void reflection_frame(vec3 world_normal, vec3 world_position, vec3 camera_position,
                      out vec3 n, out vec3 r) {
    n = normalize(world_normal);
    vec3 v = normalize(camera_position - world_position);
    if (dot(n, v) < 0.0) {
        n = -n;
    }
    r = reflect(-v, n);
}
