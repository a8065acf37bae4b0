/* result.c — glow_result_string. */
#include "glow/glow.h"

const char *glow_result_string(glow_result result) {
    switch (result) {
    case GLOW_OK: return "GLOW_OK: success";
    case GLOW_ERROR_INVALID_ARGUMENT: return "GLOW_ERROR_INVALID_ARGUMENT: a NULL or out-of-range argument";
    case GLOW_ERROR_INVALID_OPERATION: return "GLOW_ERROR_INVALID_OPERATION: not allowed in the object's current state";
    case GLOW_ERROR_OUT_OF_MEMORY: return "GLOW_ERROR_OUT_OF_MEMORY: an allocation failed";
    case GLOW_ERROR_IO: return "GLOW_ERROR_IO: a file could not be opened, read or written";
    case GLOW_ERROR_CORRUPT_DATA: return "GLOW_ERROR_CORRUPT_DATA: the input failed a structure check";
    case GLOW_ERROR_VERSION_MISMATCH: return "GLOW_ERROR_VERSION_MISMATCH: unsupported bake format or API version";
    case GLOW_ERROR_UNSUPPORTED: return "GLOW_ERROR_UNSUPPORTED: feature or file format not available";
    case GLOW_ERROR_HOST_CALLBACK: return "GLOW_ERROR_HOST_CALLBACK: a host hook failed or returned NaN/Inf";
    case GLOW_ERROR_TRUNCATED: return "GLOW_ERROR_TRUNCATED: the bake is shorter than its header or sections say";
    case GLOW_ERROR_BAD_MAGIC: return "GLOW_ERROR_BAD_MAGIC: not a Glow bake";
    case GLOW_ERROR_BAD_CHECKSUM: return "GLOW_ERROR_BAD_CHECKSUM: a CRC-32 does not match (the bake is damaged)";
    case GLOW_ERROR_OUT_OF_RANGE: return "GLOW_ERROR_OUT_OF_RANGE: an index in the bake points outside its array";
    case GLOW_ERROR_EMPTY_SCENE: return "GLOW_ERROR_EMPTY_SCENE: the scene has no usable triangles";
    case GLOW_RESULT_FORCE_U32: break;
    }
    return "GLOW_ERROR_UNKNOWN: not a glow_result value";
}
