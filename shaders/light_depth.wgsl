// Linear light depth, shared by the shadow pass (which stores it) and the
// camera and analysis passes (which compare against it); prepended to each.
//
// `position` is the homogeneous light position: (p, 1) for a point or spot
// light, (-d, 0) for a directional light travelling along d. `range` is
// (min distance, 1 / (max - min)) of the matrix's `light_distance`.
fn linear_light_depth(position: vec4<f32>, range: vec2<f32>, world: vec3<f32>) -> f32 {
    var distance: f32;
    if position.w > 0.0 {
        distance = length(world - position.xyz);
    } else {
        distance = dot(world, -position.xyz);
    }
    return (distance - range.x) * range.y;
}

