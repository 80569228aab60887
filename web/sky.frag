// mebake viewer: what a missed ray sees in `mebake render` (output/render.cpp SkyRadiance):
// the background radiance when given, else the scene's sky (uniform, or CIE overcast
// Lz (1 + 2 cos theta) / 3 with cos theta clamped at 0), tone-mapped like the surfaces.
precision highp float;

uniform vec3 forward, right, up;  // right and up scaled by the half-extent of the view
uniform int skyType;              // 0 none, 1 uniform, 2 overcast
uniform vec3 skyRadiance, skyUp;
uniform float exposure;
uniform int curve;

in vec2 ndc;
out vec4 fragColor;

float toneCurve(float radiance) {
    float x = radiance * exp2(exposure);
    if (!(x > 0.0)) return 0.0;
    float y;
    if (curve == 0) y = (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14);
    else if (curve == 1) y = x / (1.0 + x);
    else y = x;
    return clamp(y, 0.0, 1.0);
}

float encodeSrgb(float c) {
    c = clamp(c, 0.0, 1.0);
    return c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
}

void main() {
    vec3 dir = normalize(forward + right * ndc.x + up * ndc.y);
    vec3 l = vec3(0.0);
    if (skyType == 1) l = skyRadiance;
    else if (skyType == 2) l = skyRadiance * (1.0 + 2.0 * max(0.0, dot(dir, normalize(skyUp)))) / 3.0;
    vec3 display;
    for (int c = 0; c < 3; ++c) display[c] = encodeSrgb(toneCurve(l[c]));
    fragColor = vec4(display, 1.0);
}
