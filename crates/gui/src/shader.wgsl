// The viewport's scene: meshes (part, feature prisms) and tool-path lines.
// Each vertex carries an object index; the object's colour (alpha 0 =
// hidden) comes from a small texture rewritten on selection changes, so the
// geometry itself is uploaded once per plan change.

struct Uniforms {
    view_proj: mat4x4<f32>,
    // xyz: light direction
    light: vec4<f32>,
    // xyz: section plane normal, w: 1 when the section is on
    section: vec4<f32>,
    // x: section plane offset, y: 1 when the target is sRGB
    flags: vec4<f32>,
};

@group(0) @binding(0) var<uniform> u: Uniforms;
@group(0) @binding(1) var style: texture_2d<f32>;

struct VsOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) color: vec4<f32>,
    @location(1) world: vec3<f32>,
    @location(2) normal: vec3<f32>,
};

fn style_of(obj: u32) -> vec4<f32> {
    return textureLoad(style, vec2<i32>(i32(obj % 1024u), i32(obj / 1024u)), 0);
}

fn to_target(c: vec3<f32>) -> vec3<f32> {
    if (u.flags.y > 0.5) {
        // sRGB bytes to linear: the target converts back.
        return pow(c, vec3<f32>(2.2));
    }
    return c;
}

fn cut_away(world: vec3<f32>) -> bool {
    return u.section.w > 0.5 && dot(world, u.section.xyz) > u.flags.x;
}

@vertex
fn vs_mesh(@location(0) pos: vec3<f32>, @location(1) normal: vec3<f32>, @location(2) obj: u32) -> VsOut {
    var o: VsOut;
    let c = style_of(obj);
    o.pos = u.view_proj * vec4<f32>(pos, 1.0);
    if (c.a <= 0.0) {
        o.pos = vec4<f32>(0.0, 0.0, 2.0, 1.0);
    }
    o.color = c;
    o.world = pos;
    o.normal = normal;
    return o;
}

@fragment
fn fs_mesh(i: VsOut) -> @location(0) vec4<f32> {
    if (cut_away(i.world)) {
        discard;
    }
    let n = i.normal / max(length(i.normal), 1e-6);
    let l = abs(dot(n, normalize(u.light.xyz)));
    let shade = 0.4 + 0.6 * l;
    return vec4<f32>(to_target(i.color.rgb * shade), i.color.a);
}

@vertex
fn vs_line(@location(0) pos: vec3<f32>, @location(1) color: vec4<f32>, @location(2) obj: u32) -> VsOut {
    var o: VsOut;
    let c = style_of(obj);
    o.pos = u.view_proj * vec4<f32>(pos, 1.0);
    if (c.a <= 0.0) {
        o.pos = vec4<f32>(0.0, 0.0, 2.0, 1.0);
    }
    // A selected operation's path is drawn in its style colour.
    o.color = select(color, c, c.a < 0.99);
    o.color.a = 1.0;
    o.world = pos;
    o.normal = vec3<f32>(0.0, 0.0, 1.0);
    return o;
}

@fragment
fn fs_line(i: VsOut) -> @location(0) vec4<f32> {
    if (cut_away(i.world)) {
        discard;
    }
    return vec4<f32>(to_target(i.color.rgb), 1.0);
}
