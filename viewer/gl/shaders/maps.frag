#version 330 core
in vec3 g_face;
layout(location = 0) out float o_map;  // distance from the camera's centre (MIN-blended)
void main() { o_map = length(g_face); }
