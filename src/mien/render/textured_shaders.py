"""GLSL 3.30 shaders of the textured renderer: the lights of :mod:`mien.render.shaders`, on a textured albedo.

The lighting is the untextured renderer's (same :data:`~mien.render.shaders.LIGHTS`, key + fill + rim +
hemispherical ambient + a little key specular, gamma 2.2 output), so a textured head and an untextured one
look alike; only the albedo differs: ``base_color_factor * texture(uv)``, the texture stored as sRGB
(``GL_SRGB8_ALPHA8``: the sampler returns linear values, filtered and mip-mapped in linear light).

Alpha modes (glTF 2.0): OPAQUE writes alpha 1; MASK discards fragments under the cutoff; BLEND outputs the
alpha for ``SRC_ALPHA, ONE_MINUS_SRC_ALPHA`` blending over the sRGB-encoded image (as three.js blends).
Double-sided parts light their back faces with the flipped normal.

Speed on a CPU rasteriser (llvmpipe runs every ``pow`` as exp2/log2): the fragment shader comes in two
variants, with the alpha test's ``discard`` (MASK parts) and without it (so the others keep early depth
testing); the integer powers are products, and the gamma 2.2 encoding ``x ** (1 / 2.2)`` is a fit on
``x, sqrt(x), x ** 0.25, x ** 0.125`` (three square roots) within 0.17 of one 8-bit level (0.0007) on 0..1,
exact at 0: the same images as ``pow`` to within one level.
"""

from __future__ import annotations

__all__ = ["ALPHA_MODE_IDS", "GAMMA_FIT", "TEXTURED_FRAGMENT_SHADER", "TEXTURED_VERTEX_SHADER", "fragment_shader"]

ALPHA_MODE_IDS: dict[str, int] = {"OPAQUE": 0, "MASK": 1, "BLEND": 2}
"""glTF alpha mode -> the integer the fragment shader's ``u_alpha_mode`` takes."""

GAMMA_FIT: tuple[float, float, float, float] = (-0.048339, 0.930165, 0.143387, -0.025879)
"""Coefficients of ``x, sqrt(x), x ** 0.25, x ** 0.125`` whose sum approximates ``x ** (1 / 2.2)`` on 0..1
(weighted least squares toward the largest error; max error 0.17 / 255)."""

TEXTURED_VERTEX_SHADER = """
#version 330
uniform mat4 u_view_projection;
uniform mat4 u_view;
in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;
out vec3 v_normal;
out vec3 v_eye_position;
out vec2 v_uv;
void main() {
    vec4 world = vec4(in_position, 1.0);
    gl_Position = u_view_projection * world;
    v_eye_position = (u_view * world).xyz;
    v_normal = mat3(u_view) * in_normal;
    v_uv = in_uv;
}
"""

TEXTURED_FRAGMENT_SHADER = """
#version 330
uniform vec3 u_key_direction;
uniform vec3 u_key_color;
uniform vec3 u_fill_direction;
uniform vec3 u_fill_color;
uniform vec3 u_rim_direction;
uniform vec3 u_rim_color;
uniform sampler2D u_base_color;
uniform vec4 u_base_color_factor;
uniform int u_alpha_mode;
uniform float u_alpha_cutoff;
in vec3 v_normal;
in vec3 v_eye_position;
in vec2 v_uv;
out vec4 f_color;
void main() {
    vec4 base = u_base_color_factor * texture(u_base_color, v_uv);
#ifdef ALPHA_TEST
    if (base.a < u_alpha_cutoff) discard;
#endif
    vec3 albedo = base.rgb;
    // Culling keeps single-sided parts front-facing; a double-sided part's back face turns its normal round.
    vec3 n = normalize(v_normal) * (gl_FrontFacing ? 1.0 : -1.0);
    vec3 to_eye = normalize(-v_eye_position);
    float key = max(dot(n, u_key_direction), 0.0);
    float fill = max(dot(n, u_fill_direction), 0.0);
    float facing = max(dot(n, to_eye), 0.0);
    float edge = 1.0 - facing;
    float rim = edge * edge * edge * (0.35 + 0.65 * max(dot(n, u_rim_direction), 0.0));
    vec3 ambient = mix(vec3(0.05, 0.05, 0.06), vec3(0.16, 0.16, 0.17), 0.5 + 0.5 * n.y);
    vec3 half_vector = normalize(u_key_direction + to_eye);
    float h2 = max(dot(n, half_vector), 0.0);
    h2 *= h2;
    float h4 = h2 * h2;
    float h32 = h4 * h4;
    h32 *= h32;
    h32 *= h32;
    float specular = key > 0.0 ? 0.12 * h32 * h4 : 0.0;  // 0.12 * (n . h) ** 36
    vec3 linear = albedo * (u_key_color * key + u_fill_color * fill + ambient + u_rim_color * rim)
        + u_key_color * specular;
    vec3 x = clamp(linear, 0.0, 1.0);
    vec3 r2 = sqrt(x);
    vec3 r4 = sqrt(r2);
    vec3 encoded = GAMMA_X * x + GAMMA_R2 * r2 + GAMMA_R4 * r4 + GAMMA_R8 * sqrt(r4);  // x ** (1 / 2.2)
    f_color = vec4(encoded, u_alpha_mode == 2 ? base.a : 1.0);
}
"""
"""The fragment shader's body; :func:`fragment_shader` adds the ``#define`` s it needs."""


def fragment_shader(alpha_test: bool) -> str:
    """The fragment shader, with the MASK alpha test's ``discard`` when ``alpha_test``."""
    defines = "".join(
        f"#define GAMMA_{name} {value!r}\n" for name, value in zip(("X", "R2", "R4", "R8"), GAMMA_FIT, strict=True)
    )
    if alpha_test:
        defines += "#define ALPHA_TEST\n"
    version, body = TEXTURED_FRAGMENT_SHADER.split("\n", 2)[1:]
    return f"{version}\n{defines}{body}"
