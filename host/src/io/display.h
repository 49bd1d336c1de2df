// Internal (libfemto_io): the OpenColorIO display transform (linear -> sRGB) of the config
// ocio_config_path() names, loaded once per process and shared by PNG previews and
// `femto viz` frames.
#pragma once

#include <OpenColorIO/OpenColorIO.h>

namespace femto::io::detail {

/// The CPU processor of the display transform; throws std::runtime_error naming the config
/// when it cannot be loaded.
OCIO_NAMESPACE::ConstCPUProcessorRcPtr display_processor();

}  // namespace femto::io::detail
