// Writes one DICOM slice with GDCM itself, as a scanner's export holds them: a CT image of
// int16 samples with its position, orientation, spacing and rescaling, in a chosen transfer
// syntax (uncompressed or compressed). For the DICOM tests; no downloaded data.
#pragma once
#include <gdcmAttribute.h>
#include <gdcmImageChangeTransferSyntax.h>
#include <gdcmImageWriter.h>
#include <gdcmTrace.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace tessera::test {

struct DicomSlice {
  int cols = 0, rows = 0;
  std::vector<int16_t> values;  // cols x rows, along a row first
  double z = 0;                 // ImagePositionPatient's z (axial slices), mm
  double y = -30;               // and its y (moving with z: a gantry tilt)
  double sx = 0.5, sy = 0.7;    // along a row, down the rows (PixelSpacing is sy\sx)
  std::string series = "1.2.826.0.1.3680043.2.1125.1";
  std::string description = "axial";
  gdcm::TransferSyntax::TSType syntax = gdcm::TransferSyntax::ExplicitVRLittleEndian;
  double slope = 1, inter = 0;
  int bits_stored = 16;  // signed samples in the low bits, the rest of each 16 as `values` has them
  int frames = 1;        // > 1: one multi-frame file (values: cols x rows x frames)
};

inline void writeDicomSlice(const std::filesystem::path& file, const DicomSlice& s) {
  gdcm::Trace::SetWarning(false);  // "No PhotometricInterpretation found" while it writes one
  gdcm::ImageWriter w;
  gdcm::SmartPointer<gdcm::Image> im = new gdcm::Image;
  im->SetNumberOfDimensions(s.frames > 1 ? 3 : 2);
  const unsigned int dims[3] = {(unsigned)s.cols, (unsigned)s.rows, (unsigned)s.frames};
  im->SetDimensions(dims);
  gdcm::PixelFormat format(gdcm::PixelFormat::INT16);
  format.SetBitsStored((unsigned short)s.bits_stored);
  format.SetHighBit((unsigned short)(s.bits_stored - 1));
  im->SetPixelFormat(format);
  im->SetPhotometricInterpretation(gdcm::PhotometricInterpretation::MONOCHROME2);
  const double origin[3] = {-20, s.y, s.z}, cosines[6] = {1, 0, 0, 0, 1, 0};
  im->SetOrigin(origin);
  im->SetOrigin(2, origin[2]);  // a 2-D image keeps only x and y of SetOrigin(origin)
  im->SetDirectionCosines(cosines);
  im->SetSpacing(0, s.sx);
  im->SetSpacing(1, s.sy);
  im->SetSlope(s.slope);
  im->SetIntercept(s.inter);
  gdcm::DataElement pixels(gdcm::Tag(0x7fe0, 0x0010));
  pixels.SetByteValue(reinterpret_cast<const char*>(s.values.data()), (uint32_t)(s.values.size() * 2));
  im->SetDataElement(pixels);
  im->SetTransferSyntax(gdcm::TransferSyntax::ExplicitVRLittleEndian);
  if (s.syntax != gdcm::TransferSyntax::ExplicitVRLittleEndian) {
    gdcm::ImageChangeTransferSyntax change;
    change.SetTransferSyntax(s.syntax);
    change.SetInput(*im);
    ASSERT_TRUE(change.Change()) << "GDCM cannot write " << gdcm::TransferSyntax::GetTSString(s.syntax);
    w.SetImage(change.GetOutput());
  } else {
    w.SetImage(*im);
  }
  gdcm::DataSet& ds = w.GetFile().GetDataSet();
  gdcm::Attribute<0x0008, 0x0016> sop_class;
  sop_class.SetValue(gdcm::MediaStorage::GetMSString(gdcm::MediaStorage::CTImageStorage));
  ds.Replace(sop_class.GetAsDataElement());
  gdcm::Attribute<0x0020, 0x000e> series;
  series.SetValue(s.series);
  ds.Replace(series.GetAsDataElement());
  gdcm::Attribute<0x0008, 0x103e> description;
  description.SetValue(s.description);
  ds.Replace(description.GetAsDataElement());
  w.SetFileName(file.string().c_str());
  ASSERT_TRUE(w.Write()) << file;
}

}  // namespace tessera::test
