#version 330 core
layout(location = 0) in vec3 position;
uniform mat3 face_R;  // face_from_world rotation
uniform vec3 face_t;  // face-frame position of the scene's centre (the camera at the origin)
uniform vec4 map;     // sx, sy, ox, oy: ndc = (sx x / z - ox, sy y / z - oy)
uniform vec2 depth;   // A, B
out vec3 v_face;
void main() {
  vec3 c = face_R * position + face_t;
  v_face = c;
  gl_Position = vec4(map.x * c.x - map.z * c.z, map.y * c.y - map.w * c.z,
                     depth.x * c.z + depth.y, c.z);
}
