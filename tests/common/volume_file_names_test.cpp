// Volume files by their names: an .img is NIfTI's only beside its .hdr, a pair or a gzip
// stream is diagnosed from its header, and a file given alone loads by any bytes of its name
// (a raw one is said to need a scene).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "common/scene.h"
#include "tests/common/load_error.h"
#include "tests/common/temp_dir.h"
#include "tests/common/volume_files_util.h"

namespace tessera {
namespace {

using test::TempDir;
using namespace test::files;
using test::loadError;

// Found by review: an .img with no .hdr beside it (a raw dump named so) was taken for NIfTI's
// and refused; the .img of a pair with a bad header was diagnosed from the .img's bytes; a
// corrupt gzip header was "only 0 bytes".
TEST(VolumeFiles, AnImgAloneIsRawAndAPairOrGzipIsDiagnosedFromItsHeader) {
  TempDir t("img");
  const Volume ref = rawReference(t);
  std::filesystem::copy_file(t.file("ref.raw"), t.file("dump.img"));
  expectSameVolume(fromScene("volume: {file: dump.img, dims: [13, 11, 7], type: int16, spacing: [0.75, 1.25, 2.5]}\n",
                             t.path.string()),
                   ref);
  writeNifti(t.file("pair.hdr"));
  expectSameVolume(fromScene("volume: {file: pair.img}\n", t.path.string()), ref);
  {
    std::fstream h(t.file("pair.hdr"), std::ios::in | std::ios::out | std::ios::binary);
    h.seekp(40);  // dim[0]
    const int16_t nine = 9;
    h.write(reinterpret_cast<const char*>(&nine), 2);
  }
  const std::string pair = loadError("volume: {file: pair.img}\n", t.path.string());
  EXPECT_NE(pair.find("pair.img: not a readable NIfTI file: pair.hdr: dim[0] = 9"), std::string::npos) << pair;
  writeNifti(t.file("bad.nii.gz"));
  {
    std::fstream g(t.file("bad.nii.gz"), std::ios::in | std::ios::out | std::ios::binary);
    g.seekp(3);  // the gzip header's flags: reserved bits set
    g.put((char)0xe0);
  }
  const std::string gz = loadError("volume: {file: bad.nii.gz}\n", t.path.string());
  EXPECT_NE(gz.find("bad.nii.gz: not a readable NIfTI file: its gzip stream is corrupt or cut short"), std::string::npos)
      << gz;
}

// A file given alone (tessera-info FILE, TESSERA_SCENE=FILE): any bytes of its name, a quote
// or a Latin-1 'é' included; a raw volume alone is said to need a scene (it was a YAML error).
TEST(VolumeFiles, AFileGivenAloneByAnyNameOrARawFileThatNeedsAScene) {
  TempDir t("alone");
  const Volume ref = rawReference(t);
  for (const std::string name : {"it's.nii", "cr\xe9ne.nii"}) {
    writeNifti(t.file(name));
    expectSameVolume(loadVolume(loadScene(t.file(name))), ref);
  }
  // A scene saved as UTF-16 (Windows' "Unicode"): NULs in every character, and still a scene.
  {
    const std::string text = "volume: {generator: {name: hollow-shell, size: 16}}\nimage: [32, 24]\n";
    std::string utf16 = "\xff\xfe";
    for (char c : text) utf16 += c, utf16 += '\0';
    std::ofstream(t.file("wide.yaml"), std::ios::binary) << utf16;
    EXPECT_EQ(loadScene(t.file("wide.yaml")).width, 32);
  }
  try {
    loadScene(t.file("ref.raw"));
    ADD_FAILURE() << "a raw file alone loaded";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("ref.raw: not a scene file but binary data; a raw volume has no header"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("volume: {file: ref.raw, dims: [x, y, z], type: uint16}"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace tessera
