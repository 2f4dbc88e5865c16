// OpenEXR output with Debian's libopenexr: the file is built in memory (an
// OStream over a string), like every other output, so that OutputFiles can
// write it all or nothing.
#include "formats/image/image_io.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "scene/scene.h"

#ifdef OPSILA_HAVE_OPENEXR
#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStdIO.h>
#endif

namespace opsila {

#ifdef OPSILA_HAVE_OPENEXR

bool exr_available() { return true; }

std::string encode_exr(int width, int height, const std::vector<float>& rgb, bool half) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("image size must be positive");
  const std::size_t values = static_cast<std::size_t>(width) * height * 3;
  if (rgb.size() != values) throw std::invalid_argument("pixel buffer does not match the image size");
  for (float v : rgb)
    if (!std::isfinite(v)) throw std::logic_error("a pixel value is not finite; no OpenEXR file is written");
  // Half keeps the layout of the float buffer, one value per channel; values
  // beyond its range would become infinity, so they take its largest.
  std::vector<Imath::half> halves;
  if (half) {
    halves.resize(values);
    const float largest = HALF_MAX;
    for (std::size_t i = 0; i < values; ++i) halves[i] = Imath::half(std::min(rgb[i], largest));
  }
  const Imf::PixelType type = half ? Imf::HALF : Imf::FLOAT;
  const std::size_t size = half ? sizeof(Imath::half) : sizeof(float);
  char* base = half ? reinterpret_cast<char*>(halves.data()) : reinterpret_cast<char*>(const_cast<float*>(rgb.data()));
  Imf::Header header(width, height);  // ZIP compression, increasing y: row 0 = top
  Imf::FrameBuffer frame;
  const char* names[3] = {"R", "G", "B"};
  for (int c = 0; c < 3; ++c) {
    header.channels().insert(names[c], Imf::Channel(type));
    frame.insert(names[c], Imf::Slice(type, base + c * size, 3 * size, 3 * size * width));
  }
  Imf::StdOSStream stream;
  try {
    Imf::OutputFile file(stream, header, 0);  // 0: no worker threads, all on this one
    file.setFrameBuffer(frame);
    file.writePixels(height);
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("OpenEXR encoding failed: ") + e.what());
  }
  return stream.str();
}

#else  // built without OpenEXR

bool exr_available() { return false; }

std::string encode_exr(int, int, const std::vector<float>&, bool) {
  throw InputError("this build has no OpenEXR (install libopenexr-dev and rebuild)");
}

#endif

}  // namespace opsila
