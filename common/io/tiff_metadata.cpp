// What a TIFF stack's first page's description says about its axes and spacing: ImageJ's
// "ImageJ=1.54f\nimages=60\nchannels=2\nslices=30\nspacing=2.5\nunit=micron\n..." or
// OME-TIFF's XML (see tiff_metadata.h).
#include "common/io/tiff_metadata.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace tessera {
namespace {
namespace tiff_metadata {  // a unity build joins this file's helpers with others'

[[noreturn]] void fail(const std::string& file, const std::string& what) { throw std::runtime_error(file + ": " + what); }

// ImageJ writes its stack's layout and z spacing in the first page's description
// ("ImageJ=1.54f\nimages=60\nchannels=2\nslices=30\nspacing=2.5\nunit=micron\n...").
double imageJValue(const std::string& description, const std::string& key, double otherwise) {
  const size_t at = description.find("\n" + key + "=");
  return at == std::string::npos ? otherwise : std::atof(description.c_str() + at + key.size() + 2);
}

// An attribute of the OME-XML Pixels element ("<Pixels ... SizeC=\"2\" ...>"), or "".
std::string omePixels(const std::string& xml, const std::string& attribute) {
  size_t at = xml.find("Pixels ");
  while (at != std::string::npos && at > 0 && xml[at - 1] != '<' && xml[at - 1] != ':') at = xml.find("Pixels ", at + 1);
  if (at == std::string::npos) return "";
  const size_t end = xml.find('>', at);
  const std::string tag = xml.substr(at, end == std::string::npos ? std::string::npos : end - at);
  const size_t a = tag.find(" " + attribute + "=\"");
  if (a == std::string::npos) return "";
  const size_t v = a + attribute.size() + 3;
  return tag.substr(v, tag.find('"', v) - v);
}

}  // namespace tiff_metadata
}  // namespace

void applyTiffMetadata(const std::string& description, float xres, float yres, const std::string& file, RawVolumeSpec& spec) {
  namespace md = tiff_metadata;  // named, not a using-directive: the unity build's other fail()s
  spec.spacing = {0, 0, 0};  // what the metadata gives; 0: not given
  if (description.find("<OME") != std::string::npos) {
    // OME-TIFF (Bio-Formats, Micro-Manager): channels and time points are pages of the same
    // size, interleaved by DimensionOrder; one channel at one time is a volume.
    const int channels = std::atoi(md::omePixels(description, "SizeC").c_str()), times = std::atoi(md::omePixels(description, "SizeT").c_str());
    if (channels > 1 || times > 1)
      md::fail(file, "an OME-TIFF of " + std::to_string(std::max(channels, 1)) + " channels and " + std::to_string(std::max(times, 1)) +
                         " time points: Tessera renders one channel at one time; save it as its own stack (Fiji: Image > "
                         "Color > Split Channels, Image > Duplicate)");
    for (int a = 0; a < 3; ++a) {
      const double v = std::atof(md::omePixels(description, std::string("PhysicalSize") + "XYZ"[a]).c_str());
      if (v > 0) spec.spacing[a] = v;
    }
  } else if (description.rfind("ImageJ=", 0) == 0) {
    const double channels = md::imageJValue(description, "channels", 1), frames = md::imageJValue(description, "frames", 1);
    const double slices = md::imageJValue(description, "slices", 1);
    for (const auto& [key, v] : {std::pair{"channels", channels}, {"frames", frames}, {"slices", slices}})
      if (!(v >= 1 && v <= 65536 && v == std::floor(v)))
        md::fail(file, std::string("ImageJ's metadata says ") + key + "=" + std::to_string(v) + ": not a count of 1..65536");
    // One axis only, but not z: a stack saved without its axes (tifffile's imagej=True calls
    // every page a channel) or labelled wrongly. Read as z, and said.
    if ((channels > 1) + (frames > 1) + (slices > 1) == 1 && slices == 1) {
      const bool c = channels > 1;
      spec.notes.push_back("ImageJ's metadata in " + std::filesystem::path(file).filename().string() + " calls its " +
                           std::to_string((int)(c ? channels : frames)) + (c ? " pages channels" : " pages time points") +
                           "; Tessera reads them as z slices (to say so in the file: Fiji's Image > Properties, or "
                           "tifffile's metadata={'axes': 'ZYX'}). If they are " +
                           (c ? "channels, split them (Fiji: Image > Color > Split Channels)"
                              : "a time-lapse of one plane, this stacks time along z"));
    } else if (channels > 1) {
      md::fail(file, "an ImageJ hyperstack of " + std::to_string((int)channels) +
                         " channels: Tessera renders one; save one channel (Fiji: Image > Color > Split Channels)");
    } else if (frames > 1) {
      md::fail(file, "an ImageJ hyperstack of " + std::to_string((int)frames) +
                         " time points: save each as its own stack and list them as the scene's volume.series");
    }
    const double images = md::imageJValue(description, "images", (double)spec.slices.size());
    if (images > (double)spec.slices.size())
      md::fail(file, "ImageJ wrote " + std::to_string((long long)std::min(images, 1e18)) + " images but the file has " +
                         std::to_string(spec.slices.size()) + " pages (ImageJ saves a stack over 4 GB that way): save it as raw "
                         "data and give volume.dims and type");
    // Resolution in pixels per unit; the same unit for the slices' spacing.
    if (xres > 0) spec.spacing[0] = 1.0 / xres;
    if (yres > 0) spec.spacing[1] = 1.0 / yres;
    spec.spacing[2] = std::fabs(md::imageJValue(description, "spacing", 0));  // ImageJ keeps a negative one's size
  }
  // What neither ImageJ's nor OME's metadata gave: 1, and a warning (volumeWarnings).
  for (int a = 0; a < 3; ++a)
    if (!(spec.spacing[a] > 0)) spec.spacing[a] = 1, spec.spacing_known[a] = false;
}

}  // namespace tessera
