#version 330 core
// Distance maps of every camera to draw, in one instanced draw (maps.geom routes each instance
// to its layer): the vertex as it is, with its instance.
layout(location = 0) in vec3 position;  // relative to the scene's centre
out vec3 v_position;
flat out int v_instance;
void main() {
  v_position = position;
  v_instance = gl_InstanceID;
  gl_Position = vec4(0.0);
}
