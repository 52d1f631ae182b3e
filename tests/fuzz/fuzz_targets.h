#pragma once
/// \file fuzz_targets.h
/// The fuzzed entry points, shared by the libFuzzer targets (clang, tests/fuzz/clang) and the
/// replay driver (the normal build, fuzz_replay.cpp). Each runs one input; only pandora::InputError
/// may escape. docs/robustness.md says how they are run and what they found.

#include <cstddef>
#include <cstdint>

namespace pandora::fuzz {

/// Bytes as a fields.vdb: ReadFieldsVdbBytes, then CheckFieldsProvenance against a fixed two-camera
/// scene (tests/data/minimal.json, built in), then every value of every grid read.
void FieldsTarget(const std::uint8_t* data, std::size_t size);

/// Bytes as a scene file: ParseScene(text, MESH_DIR/fuzz.json) with meshes loaded, so relative mesh
/// references resolve in tests/fuzz/meshes. Parses and validates only (no ray caster, no fields).
void SceneTarget(const std::uint8_t* data, std::size_t size);

/// Bytes as a viewer script (`pandora view --script`): viewer::ParseScript, parse and validate
/// only.
void ScriptTarget(const std::uint8_t* data, std::size_t size);

/// Bytes as a calibrated rig (`pandora import-rig`): the first byte picks OpenCV YAML (even) or a
/// COLMAP model (odd; cameras.txt, then "\n@images\n", then images.txt); every value read finite.
void RigTarget(const std::uint8_t* data, std::size_t size);

}  // namespace pandora::fuzz
