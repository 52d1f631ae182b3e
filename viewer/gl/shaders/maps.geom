#version 330 core
// One triangle into one distance map: instance i of the draw is map i of the pass (a camera's
// perspective map or a cube face), whose frame, projection and layer the block holds. No depth
// range is needed: the maps keep the nearest distance by MIN blending, not a depth test, so only
// what lies behind the map's plane (nearer than `near` along its axis) is clipped.
layout(triangles) in;
layout(triangle_strip, max_vertices = 3) out;
in vec3 v_position[];
flat in int v_instance[];
// Per map, 5 vec4: the rows of face_from_world's rotation with the face-frame position of the
// scene's centre in w; (sx, sy, ox, oy) with ndc = (sx x / z - ox, sy y / z - oy); (layer, near).
layout(std140) uniform MapBlock { vec4 map_data[5 * MAX_MAPS]; };
out vec3 g_face;
void main() {
  int b = 5 * v_instance[0];
  vec4 r0 = map_data[b], r1 = map_data[b + 1], r2 = map_data[b + 2], m = map_data[b + 3];
  vec4 extra = map_data[b + 4];
  mat3 R = transpose(mat3(r0.xyz, r1.xyz, r2.xyz));  // rows -> face_from_world
  vec3 t = vec3(r0.w, r1.w, r2.w);
  for (int i = 0; i < 3; ++i) {
    vec3 c = R * v_position[i] + t;
    g_face = c;
    gl_Layer = int(extra.x + 0.5);
    gl_Position = vec4(m.x * c.x - m.z * c.z, m.y * c.y - m.w * c.z, c.z - 2.0 * extra.y, c.z);
    EmitVertex();
  }
  EndPrimitive();
}
