#pragma once
// GenICam pixel formats (as Aravis numbers them) <-> ivoa image_t formats.
// Only 8-bit layouts the rest of the system decodes are mapped.
#include <cstdint>
#include <optional>

namespace ivoa::aravis_stereo {

// The GenICam names of the mapped formats, for help and error messages.
inline constexpr const char* kMappedPixelFormats = "BayerRG8, BayerBG8, BayerGB8, BayerGR8, Mono8, RGB8, BGR8";

// ARV_PIXEL_FORMAT_* -> image_t::PIXEL_FORMAT_*; nothing if unmapped.
std::optional<int32_t> ivoa_pixelformat_from_genicam(uint32_t arv_pixel_format);

}  // namespace ivoa::aravis_stereo
