// Lit, instanced unit primitives (box, cylinder, sphere) for the robot geometry.
// Each instance carries its model matrix (unit primitive -> body frame, mm, scale included),
// the matching normal matrix and a colour. Lighting: Lambert from a head light plus ambient.

struct Frame {
    view_proj: mat4x4<f32>,
    // xyz: direction towards the light (world), w: ambient factor.
    light_dir: vec4<f32>,
    // xyz: camera position (world), w: unused.
    eye: vec4<f32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
};

struct InstanceIn {
    @location(2) m0: vec4<f32>,
    @location(3) m1: vec4<f32>,
    @location(4) m2: vec4<f32>,
    @location(5) m3: vec4<f32>,
    @location(6) n0: vec4<f32>,
    @location(7) n1: vec4<f32>,
    @location(8) n2: vec4<f32>,
    @location(9) color: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) color: vec4<f32>,
    @location(2) world: vec3<f32>,
};

@vertex
fn vs_main(v: VertexIn, i: InstanceIn) -> VertexOut {
    let model = mat4x4<f32>(i.m0, i.m1, i.m2, i.m3);
    let normal_matrix = mat3x3<f32>(i.n0.xyz, i.n1.xyz, i.n2.xyz);
    let world = model * vec4<f32>(v.position, 1.0);
    var out: VertexOut;
    out.clip = frame.view_proj * world;
    out.normal = normalize(normal_matrix * v.normal);
    out.color = i.color;
    out.world = world.xyz;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    var n = normalize(in.normal);
    // Light both faces of open or inverted geometry.
    let to_eye = normalize(frame.eye.xyz - in.world);
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    let l = normalize(frame.light_dir.xyz);
    let ambient = frame.light_dir.w;
    let diffuse = max(dot(n, l), 0.0) * (1.0 - ambient);
    let shade = ambient + diffuse;
    return vec4<f32>(in.color.rgb * shade, in.color.a);
}
