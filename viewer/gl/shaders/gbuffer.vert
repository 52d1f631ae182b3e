#version 330 core
layout(location = 0) in vec3 position;  // relative to the scene's centre
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 albedo;
layout(location = 3) in vec2 tag;  // object index, drawn-edge bits (bit i: edge opposite vertex i)
layout(location = 4) in vec2 uv;   // texture coordinate (v = 0: the texture's bottom row)
uniform mat3 view_R;   // camera_from_world rotation of the eye (OpenCV frame: y down, z forward)
uniform vec3 view_t;   // camera-frame position of the scene's centre, less (0, 0, view_d0)
uniform float view_d0; // the near plane's depth: z is kept relative to it (precision far away)
uniform vec4 proj;     // 2f/W, 2f/H, A, B': clip = (proj.x x, proj.y y, A z + B', z + d0)
uniform vec2 proj_offset;  // an off-centre pyramid (a camera's-eye cover): clip.xy -= offset w
out vec3 v_position;
out float v_z;         // depth beyond the near plane, m (the fragment's depth and the cut)
flat out vec3 v_normal;
flat out vec3 v_albedo;
flat out vec2 v_tag;
out vec3 v_bary;
out vec2 v_uv;
void main() {
  vec3 c = view_R * position + view_t;  // c.z: depth less view_d0
  v_uv = uv;
  v_z = c.z;
  float w = c.z + view_d0;
  gl_Position = vec4(proj.x * c.x - proj_offset.x * w, proj.y * c.y - proj_offset.y * w,
                     proj.z * c.z + proj.w, w);
  v_position = position;
  v_normal = normal;
  v_albedo = albedo;
  v_tag = tag;
  int corner = gl_VertexID % 3;  // non-indexed triangles: vertex i of its triangle
  v_bary = vec3(corner == 0 ? 1.0 : 0.0, corner == 1 ? 1.0 : 0.0, corner == 2 ? 1.0 : 0.0);
}
