// fivebar::runtime from an install prefix: its C API refuses a malformed configuration with a
// message. Exit 0 when it does.
#include <cstdio>
#include <cstring>

#include "fivebar/runtime/c_api.h"

int main() {
  char error[256] = {0};
  const char text[] = "{not json";
  fivebar_runtime* r = fivebar_runtime_create_from_json(text, std::strlen(text), error, sizeof error);
  if (r != nullptr || error[0] == '\0') {
    std::fprintf(stderr, "runtime: a malformed configuration was accepted\n");
    if (r != nullptr) fivebar_runtime_destroy(r);
    return 1;
  }
  std::printf("runtime: refused: %s\n", error);
  return 0;
}
