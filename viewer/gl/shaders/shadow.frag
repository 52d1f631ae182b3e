#version 330 core
in vec3 v_face;
layout(location = 0) out float o_map;  // distance from the camera's centre
void main() { o_map = length(v_face); }
