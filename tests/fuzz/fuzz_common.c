#include <stdio.h>
#include <stdlib.h>

#include "fuzz_target.h"

uint64_t hapfluid_fuzz_accepted = 0;

void hapfluid_fuzz_violated(const char* what) {
  fprintf(stderr, "fuzz: property violated: %s\n", what);
  abort();
}
