/* What every harness in this folder implements (libFuzzer's entry point) and shares with the
 * replay driver of the normal build (replay_main.cpp). C and C++. */
#pragma once

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

/* Inputs the code under test accepted as valid (decoded, parsed, attached). The replay driver
 * can require every seed to be accepted, so a seed corpus that stopped being valid is noticed. */
extern uint64_t hapfluid_fuzz_accepted;

/* A property the code under test broke: prints which and aborts, a crash to libFuzzer. */
void hapfluid_fuzz_violated(const char* what);

#ifdef __cplusplus
}
#endif
