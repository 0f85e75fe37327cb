#include "ivoa/aravis_stereo/pixel_formats.hpp"

#include <arv.h>

#include "ivoa/image_t.hpp"

namespace ivoa::aravis_stereo {
namespace {

struct Mapping {
  uint32_t genicam;
  int32_t ivoa;
};

// GenICam names the Bayer layout by its first row: BayerRG8 is R G R G.
constexpr Mapping kMappings[] = {
    {ARV_PIXEL_FORMAT_MONO_8, image_t::PIXEL_FORMAT_GRAY},
    {ARV_PIXEL_FORMAT_BAYER_RG_8, image_t::PIXEL_FORMAT_BAYER_RGGB},
    {ARV_PIXEL_FORMAT_BAYER_BG_8, image_t::PIXEL_FORMAT_BAYER_BGGR},
    {ARV_PIXEL_FORMAT_BAYER_GB_8, image_t::PIXEL_FORMAT_BAYER_GBRG},
    {ARV_PIXEL_FORMAT_BAYER_GR_8, image_t::PIXEL_FORMAT_BAYER_GRBG},
    {ARV_PIXEL_FORMAT_RGB_8_PACKED, image_t::PIXEL_FORMAT_RGB},
    {ARV_PIXEL_FORMAT_BGR_8_PACKED, image_t::PIXEL_FORMAT_BGR},
};

}  // namespace

std::optional<int32_t> ivoa_pixelformat_from_genicam(uint32_t arv_pixel_format) {
  for (const auto& m : kMappings)
    if (m.genicam == arv_pixel_format) return m.ivoa;
  return std::nullopt;
}

}  // namespace ivoa::aravis_stereo
