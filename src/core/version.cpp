#include "limn/version.hpp"

namespace limn {
const char* version() {
  return LIMN_VERSION_STRING;
}
}  // namespace limn
