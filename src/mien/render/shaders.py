"""GLSL 3.30 shaders of the offscreen renderer: three lights that follow the camera, in linear light.

Lighting (directions in eye space, pointing toward the light; the camera looks along -z):

- key: from the viewer's upper left, warm, Lambert + a little Blinn-Phong specular (skin sheen);
- fill: from the viewer's right and slightly below, cool and weak, so shadowed creases keep their shape;
- rim: a Fresnel-like edge term (tinted by the albedo) strongest where light from behind grazes the silhouette;
- a hemispherical ambient (brighter from above) so nothing is pitch black.

Albedo is linear RGB: the vertex colour, under a premultiplied RGBA paint texture (brows, lash lines, lips)
sampled at the vertex's (u, v) and applied with the vertex's paint strength (texcoord's third component; 0
where a mesh has no paint). The output is sRGB-encoded (gamma 2.2) 8-bit colour.
"""

from __future__ import annotations

__all__ = ["FRAGMENT_SHADER", "LIGHTS", "VERTEX_SHADER"]

LIGHTS: dict[str, tuple[tuple[float, float, float], tuple[float, float, float]]] = {
    "key": ((-0.55, 0.55, 0.65), (1.00, 0.95, 0.88)),
    "fill": ((0.75, -0.10, 0.55), (0.22, 0.25, 0.30)),
    "rim": ((0.30, 0.45, -0.85), (0.55, 0.58, 0.65)),
}
"""Light name -> (eye-space direction toward the light, linear RGB intensity)."""

VERTEX_SHADER = """
#version 330
uniform mat4 u_view_projection;
uniform mat4 u_view;
in vec3 in_position;
in vec3 in_normal;
in vec3 in_color;
in vec3 in_texcoord;
out vec3 v_normal;
out vec3 v_eye_position;
out vec3 v_color;
out vec3 v_texcoord;
void main() {
    vec4 world = vec4(in_position, 1.0);
    gl_Position = u_view_projection * world;
    v_eye_position = (u_view * world).xyz;
    v_normal = mat3(u_view) * in_normal;
    v_color = in_color;
    v_texcoord = in_texcoord;
}
"""

FRAGMENT_SHADER = """
#version 330
uniform vec3 u_key_direction;
uniform vec3 u_key_color;
uniform vec3 u_fill_direction;
uniform vec3 u_fill_color;
uniform vec3 u_rim_direction;
uniform vec3 u_rim_color;
uniform float u_normal_sign;
uniform sampler2D u_paint;
in vec3 v_normal;
in vec3 v_eye_position;
in vec3 v_color;
in vec3 v_texcoord;
out vec4 f_color;
void main() {
    vec4 paint = texture(u_paint, v_texcoord.xy) * clamp(v_texcoord.z, 0.0, 1.0);
    vec3 albedo = v_color * (1.0 - paint.a) + paint.rgb;
    vec3 n = normalize(v_normal) * u_normal_sign;
    vec3 to_eye = normalize(-v_eye_position);
    float key = max(dot(n, u_key_direction), 0.0);
    float fill = max(dot(n, u_fill_direction), 0.0);
    float facing = max(dot(n, to_eye), 0.0);
    float rim = pow(1.0 - facing, 3.0) * (0.35 + 0.65 * max(dot(n, u_rim_direction), 0.0));
    vec3 ambient = mix(vec3(0.05, 0.05, 0.06), vec3(0.16, 0.16, 0.17), 0.5 + 0.5 * n.y);
    vec3 half_vector = normalize(u_key_direction + to_eye);
    float specular = key > 0.0 ? 0.12 * pow(max(dot(n, half_vector), 0.0), 36.0) : 0.0;
    vec3 linear = albedo * (u_key_color * key + u_fill_color * fill + ambient + u_rim_color * rim)
        + u_key_color * specular * (1.0 - 0.8 * paint.a);
    f_color = vec4(pow(clamp(linear, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
"""
