// tinyobjloader's implementation, compiled into the plugin for fuzzing builds (FEMTO_FUZZ) only:
// Debian's libtinyobjloader.so has neither coverage nor sanitizers, so the fuzzer could neither
// steer into its parser nor see its memory errors. The header is the one the .so was built from.
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>
