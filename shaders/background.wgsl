// Full-screen vertical gradient drawn first into the viewport's own colour target.

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) t: f32,
};

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> VertexOut {
    // One triangle covering the whole target.
    let x = f32((index << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(index & 2u) * 2.0 - 1.0;
    var out: VertexOut;
    out.clip = vec4<f32>(x, y, 0.0, 1.0);
    out.t = clamp(y * 0.5 + 0.5, 0.0, 1.0);
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let bottom = vec3<f32>(0.018, 0.020, 0.026);
    let top = vec3<f32>(0.070, 0.080, 0.100);
    return vec4<f32>(mix(bottom, top, in.t), 1.0);
}
