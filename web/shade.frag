// mebake viewer: the seed's display (Master-Element paper, "Display") on the GPU, the same
// arithmetic as the CPU's `mebake render` (src/solve/shading.cpp, src/output/tonemap.cpp):
//   light map  L = B / pi, B from the light-map texture;
//   diffuse    B = pi Le + rho (n . E)+ per colour, E from the three vector-irradiance maps
//              (x, y, z components, one RGB texture each), n and rho from the mesh;
//   glossy     L = (1 - w) B / pi + sum_c w rho_c |E_c| (k + 2) / (2 pi) (r . v)+^k (n . e_c)+
//              with e_c = E_c / |E_c|, r its mirror direction about n, v towards the eye:
//              the seed's L ~ Le + |E| fr(x, x + E, z) with a normalized Phong lobe.
// Then exposure, the tone curve and sRGB encoding, as every PNG mebake writes.
precision highp float;

const float PI = 3.14159265358979;

uniform sampler2D lightMap, irradianceX, irradianceY, irradianceZ;
uniform int mode;          // 0 light map, 1 vector-irradiance diffuse, 2 glossy
uniform bool radiosity;    // the solution holds B, not E: diffuse and glossy show B
uniform float exposure;    // EV
uniform int curve;         // 0 filmic, 1 reinhard, 2 clamp
uniform vec3 eye;
uniform vec3 albedo;       // the material's
uniform vec3 emission;     // radiance
uniform bool useVertexColors;
uniform float colorFactor;
uniform float glossyExponent;
uniform float glossyWeight;
uniform bool leaves;       // outline the quadtree leaves (light-map alpha = 1 + leaf level)

in vec3 vPosition;
in vec3 vNormal;
in vec2 vAtlasUv;
in vec2 vChartUv;
in vec4 vColor;

out vec4 fragColor;

float srgbToLinear(float c) {
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

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

vec3 surfaceAlbedo() {
    vec3 a = albedo;
    // All three corners coloured: alpha interpolates to 1 (shading.cpp SurfaceAlbedo).
    if (useVertexColors && vColor.a > 0.999)
        for (int c = 0; c < 3; ++c)
            a[c] = min(0.99, srgbToLinear(vColor[c]) * colorFactor);
    return a;
}

vec3 shade() {
    vec2 st = vAtlasUv;  // maps are uploaded top row first: glTF's uv is the texture's
    if (mode == 0 || radiosity) {
        vec3 b = max(texture(lightMap, st).rgb, 0.0);
        return b / PI;
    }
    vec3 n = normalize(vNormal);
    vec3 rho = surfaceAlbedo();
    vec3 ex = texture(irradianceX, st).rgb, ey = texture(irradianceY, st).rgb,
         ez = texture(irradianceZ, st).rgb;
    vec3 b = emission * PI;
    vec3 e[3];
    for (int c = 0; c < 3; ++c) {
        e[c] = vec3(ex[c], ey[c], ez[c]);
        b[c] += rho[c] * max(0.0, dot(n, e[c]));
    }
    b = max(b, 0.0);
    vec3 diffuse = b / PI;
    if (mode == 1 || glossyExponent <= 0.0 || glossyWeight <= 0.0) return diffuse;
    vec3 v = normalize(eye - vPosition);
    vec3 l = diffuse * (1.0 - glossyWeight);
    for (int c = 0; c < 3; ++c) {
        float mag = length(e[c]);
        if (mag <= 0.0) continue;
        vec3 wi = e[c] / mag;
        vec3 r = n * (2.0 * dot(n, wi)) - wi;
        float cosR = max(0.0, dot(r, v));
        float lobe = (glossyExponent + 2.0) / (2.0 * PI) * pow(cosR, glossyExponent);
        l[c] += glossyWeight * rho[c] * mag * lobe * max(0.0, dot(n, wi));
    }
    return max(l, 0.0);
}

void main() {
    // The back of a surface is black, as in `mebake render`: light lives on the front.
    vec3 radiance = gl_FrontFacing ? shade() : vec3(0.0);
    vec3 display;
    for (int c = 0; c < 3; ++c) display[c] = encodeSrgb(toneCurve(radiance[c]));
    if (leaves) {
        // The leaf's level at this texel (no filtering), then the distance in pixels to
        // the nearest line of that level's grid in the chart's square.
        vec2 st = vAtlasUv;
        ivec2 size = textureSize(lightMap, 0);
        ivec2 texel = clamp(ivec2(st * vec2(size)), ivec2(0), size - 1);
        float level = texelFetch(lightMap, texel, 0).a - 1.0;
        if (level >= 0.0) {
            vec2 g = vChartUv * exp2(floor(level + 0.5));
            vec2 d = abs(fract(g - 0.5) - 0.5) / max(fwidth(g), vec2(1e-6));
            display = mix(vec3(0.1, 0.85, 1.0), display, clamp(min(d.x, d.y), 0.0, 1.0));
        }
    }
    fragColor = vec4(display, 1.0);
}
