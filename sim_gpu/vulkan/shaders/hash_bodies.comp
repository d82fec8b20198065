#version 450
#extension GL_GOOGLE_include_directive : require
// The dynamic body particles through the same hashing pass.
#define BODIES
#include "common.glsl"
#include "hash_main.glsl"
