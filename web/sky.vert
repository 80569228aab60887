// mebake viewer: a full-screen triangle behind everything; ndc goes to sky.frag.
precision highp float;
in vec3 position;
out vec2 ndc;
void main() {
    ndc = position.xy;
    gl_Position = vec4(position.xy, 1.0, 1.0);
}
