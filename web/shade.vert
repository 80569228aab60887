// mebake viewer: a surface point's world position, normal, light-map (atlas) uv, chart uv
// and scan colour, interpolated for shade.frag.
precision highp float;

uniform mat4 modelMatrix, viewMatrix, projectionMatrix;

in vec3 position;
in vec3 normal;
in vec2 uv;   // TEXCOORD_0: atlas uv, origin top-left (glTF)
in vec2 uv1;  // TEXCOORD_1: the chart's master-element uv
#ifdef HAS_COLOR
in vec4 color;  // COLOR_0: the scan's colour as read (sRGB), alpha 0 = none
#endif

out vec3 vPosition;
out vec3 vNormal;
out vec2 vAtlasUv;
out vec2 vChartUv;
out vec4 vColor;

void main() {
    vec4 world = modelMatrix * vec4(position, 1.0);
    vPosition = world.xyz;
    vNormal = mat3(modelMatrix) * normal;
    vAtlasUv = uv;
    vChartUv = uv1;
#ifdef HAS_COLOR
    vColor = color;
#else
    vColor = vec4(0.0);
#endif
    gl_Position = projectionMatrix * viewMatrix * world;
}
