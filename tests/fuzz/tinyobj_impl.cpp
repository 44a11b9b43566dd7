// tinyobjloader compiled from its header, so that the fuzzer instruments (and covers) it; the
// same settings as Debian's libtinyobjloader_double.
#define TINYOBJLOADER_USE_DOUBLE
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>
