"""GLSL 3.30 shaders of the textured renderer: the lights of :mod:`mien.render.shaders`, on a textured albedo.

The lighting is the untextured renderer's (same :data:`~mien.render.shaders.LIGHTS`, key + fill + rim +
hemispherical ambient + a little key specular, gamma 2.2 output), so a textured head and an untextured one
look alike; only the albedo differs: ``base_color_factor * texture(uv)``, the texture stored as sRGB
(``GL_SRGB8_ALPHA8``: the sampler returns linear values, filtered and mip-mapped in linear light).

Alpha modes (glTF 2.0): OPAQUE writes alpha 1; MASK discards fragments under the cutoff; BLEND outputs the
alpha for ``SRC_ALPHA, ONE_MINUS_SRC_ALPHA`` blending over the sRGB-encoded image (as three.js blends).
Double-sided parts light their back faces with the flipped normal.

Speed on a CPU rasteriser (llvmpipe pays for every instruction of every pixel): by default the diffuse
light (key, fill, rim, ambient: smooth in the normal) is evaluated per vertex, for the front and the back
side, and interpolated, as are the key light's ``n . h`` and ``n . l``; the specular power
``0.12 (n . h) ** 36`` of the interpolated ``n . h``, the texture and the encoding stay per pixel. On a head's
dense mesh this is the per-pixel image to within a level or two (``per_pixel=True`` evaluates it all per
pixel, exactly as :mod:`mien.render.shaders`). The alpha test's ``discard`` is compiled only into the
program of MASK parts (the others keep early depth testing); integer powers are products, and the gamma 2.2
encoding ``x ** (1 / 2.2)`` is a fit on ``x, sqrt(x), x ** 0.25, x ** 0.125`` (three square roots) within
0.17 of one 8-bit level on 0..1, exact at 0.
"""

from __future__ import annotations

__all__ = ["ALPHA_MODE_IDS", "GAMMA_FIT", "fragment_shader", "vertex_shader"]

ALPHA_MODE_IDS: dict[str, int] = {"OPAQUE": 0, "MASK": 1, "BLEND": 2}
"""glTF alpha mode -> the integer the fragment shader's ``u_alpha_mode`` takes."""

GAMMA_FIT: tuple[float, float, float, float] = (-0.048339, 0.930165, 0.143387, -0.025879)
"""Coefficients of ``x, sqrt(x), x ** 0.25, x ** 0.125`` whose sum approximates ``x ** (1 / 2.2)`` on 0..1
(weighted least squares toward the largest error; max error 0.17 / 255)."""

_LIGHT_UNIFORMS = """
uniform vec3 u_key_direction;
uniform vec3 u_key_color;
uniform vec3 u_fill_direction;
uniform vec3 u_fill_color;
uniform vec3 u_rim_direction;
uniform vec3 u_rim_color;
"""

_DIFFUSE = """
// Irradiance of mien.render.shaders' lights on a surface of eye-space unit normal n seen along to_eye.
vec3 diffuse(vec3 n, vec3 to_eye) {
    float key = max(dot(n, u_key_direction), 0.0);
    float fill = max(dot(n, u_fill_direction), 0.0);
    float edge = 1.0 - max(dot(n, to_eye), 0.0);
    float rim = edge * edge * edge * (0.35 + 0.65 * max(dot(n, u_rim_direction), 0.0));
    vec3 ambient = mix(vec3(0.05, 0.05, 0.06), vec3(0.16, 0.16, 0.17), 0.5 + 0.5 * n.y);
    return u_key_color * key + u_fill_color * fill + ambient + u_rim_color * rim;
}
"""

_VERTEX_BODY = """
uniform mat4 u_view_projection;
uniform mat4 u_view;
in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;
out vec3 v_normal;
out vec3 v_eye_position;
out vec2 v_uv;
#ifdef PER_VERTEX_DIFFUSE
out vec3 v_front_light;
out vec3 v_back_light;
out vec2 v_key_dots;
#endif
void main() {
    vec4 world = vec4(in_position, 1.0);
    gl_Position = u_view_projection * world;
    v_eye_position = (u_view * world).xyz;
    v_normal = mat3(u_view) * in_normal;
    v_uv = in_uv;
#ifdef PER_VERTEX_DIFFUSE
    vec3 n = normalize(v_normal);
    vec3 to_eye = normalize(-v_eye_position);
    v_front_light = diffuse(n, to_eye);
    v_back_light = diffuse(-n, to_eye);
    // n . h and n . key for the front side (the back side's are their negatives).
    v_key_dots = vec2(dot(n, normalize(u_key_direction + to_eye)), dot(n, u_key_direction));
#endif
}
"""

_FRAGMENT_BODY = """
uniform sampler2D u_base_color;
uniform vec4 u_base_color_factor;
uniform int u_alpha_mode;
uniform float u_alpha_cutoff;
in vec3 v_normal;
in vec3 v_eye_position;
in vec2 v_uv;
#ifdef PER_VERTEX_DIFFUSE
in vec3 v_front_light;
in vec3 v_back_light;
in vec2 v_key_dots;
#endif
out vec4 f_color;
void main() {
    vec4 base = u_base_color_factor * texture(u_base_color, v_uv);
#ifdef ALPHA_TEST
    if (base.a < u_alpha_cutoff) discard;
#endif
    // Culling keeps single-sided parts front-facing; a double-sided part's back face turns its normal round.
    float side = gl_FrontFacing ? 1.0 : -1.0;
#ifdef PER_VERTEX_DIFFUSE
    vec3 light = gl_FrontFacing ? v_front_light : v_back_light;
    float n_dot_h = side * v_key_dots.x;
    float n_dot_key = side * v_key_dots.y;  // only its sign is used
#else
    vec3 n = normalize(v_normal) * side;
    vec3 to_eye = normalize(-v_eye_position);
    vec3 light = diffuse(n, to_eye);
    float n_dot_h = dot(n, normalize(u_key_direction + to_eye));
    float n_dot_key = dot(n, u_key_direction);
#endif
    float h2 = max(n_dot_h, 0.0);
    h2 *= h2;
    float h4 = h2 * h2;
    float h32 = h4 * h4;
    h32 *= h32;
    h32 *= h32;
    float specular = n_dot_key > 0.0 ? 0.12 * h32 * h4 : 0.0;  // 0.12 * (n . h) ** 36
    vec3 x = clamp(base.rgb * light + u_key_color * specular, 0.0, 1.0);
    vec3 r2 = sqrt(x);
    vec3 r4 = sqrt(r2);
    vec3 encoded = GAMMA_X * x + GAMMA_R2 * r2 + GAMMA_R4 * r4 + GAMMA_R8 * sqrt(r4);  // x ** (1 / 2.2)
    f_color = vec4(encoded, u_alpha_mode == 2 ? base.a : 1.0);
}
"""


def _defines(per_pixel: bool, alpha_test: bool = False) -> str:
    lines = ["#version 330"]
    lines += [f"#define GAMMA_{name} {value!r}" for name, value in zip(("X", "R2", "R4", "R8"), GAMMA_FIT, strict=True)]
    if not per_pixel:
        lines.append("#define PER_VERTEX_DIFFUSE")
    if alpha_test:
        lines.append("#define ALPHA_TEST")
    return "\n".join(lines) + "\n"


def vertex_shader(per_pixel: bool = False) -> str:
    """GLSL 3.30 vertex shader; it lights the vertex (both sides) unless ``per_pixel``."""
    return _defines(per_pixel) + _LIGHT_UNIFORMS + _DIFFUSE + _VERTEX_BODY


def fragment_shader(alpha_test: bool, per_pixel: bool = False) -> str:
    """GLSL 3.30 fragment shader, with the MASK alpha test's ``discard`` when ``alpha_test``."""
    return _defines(per_pixel, alpha_test) + _LIGHT_UNIFORMS + _DIFFUSE + _FRAGMENT_BODY
