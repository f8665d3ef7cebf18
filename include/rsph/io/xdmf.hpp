#pragma once
// XDMF descriptions of HDF5 snapshots, so that ParaView, VisIt or meshio open a run directly: snap_NNNNN.xmf
// beside each snap_NNNNN.h5 (the particles as a polyvertex, every field a point attribute), and
// snapshots.xmf, the temporal collection of every snapshot in the folder.
#include "rsph/io/atomic_file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace rsph::io {

/// A field of a snapshot as XDMF sees it: its dataset and how many components per particle.
struct XdmfField {
  std::string name;
  int components = 1;
};

namespace detail {

inline std::string xdmf_item(const std::string& h5, const std::string& dataset, std::size_t n, int components) {
  const std::string dims = components > 1 ? fmt::format("{} {}", n, components) : fmt::format("{}", n);
  return fmt::format(R"(<DataItem Dimensions="{}" NumberType="Float" Precision="8" Format="HDF">{}:/{}</DataItem>)",
                     dims, h5, dataset);
}

/// The <Grid> of one snapshot: positions from `geometry` (N x 2 as XY, N x 3 as XYZ), the fields as attributes;
/// its time in a comment (a lone grid with a <Time> is refused by some readers), which the series turns into one.
inline std::string xdmf_grid(const std::string& h5, std::size_t n, double time, const std::string& geometry,
                             int geometry_components, const std::vector<XdmfField>& fields) {
  std::string g = fmt::format(R"(    <Grid Name="particles" GridType="Uniform">
      <!-- time {:.17g} -->
      <Topology TopologyType="Polyvertex" NumberOfElements="{}" NodesPerElement="1"><DataItem Dimensions="{} 1" NumberType="UInt" Precision="8" Format="HDF">{}:/index</DataItem></Topology>
      <Geometry GeometryType="{}">{}</Geometry>
)",
                              time, n, n, h5, geometry_components == 2 ? "XY" : "XYZ",
                              xdmf_item(h5, geometry, n, geometry_components));
  for (const auto& f : fields)
    g += fmt::format(R"(      <Attribute Name="{}" AttributeType="{}" Center="Node">{}</Attribute>
)",
                     f.name, f.components > 1 ? "Vector" : "Scalar", xdmf_item(h5, f.name, n, f.components));
  return g + "    </Grid>\n";
}

inline std::string xdmf_document(const std::string& body) {
  return "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n  <Domain>\n" + body + "  </Domain>\n</Xdmf>\n";
}

}  // namespace detail

/// Writes snap_NNNNN.xmf beside the snapshot `h5` (N particles at `time`; positions in `geometry`, with
/// geometry_components 2 or 3), then snapshots.xmf over every snapshot description in the folder, in order.
inline void write_xdmf(const std::filesystem::path& h5, std::size_t n, double time, const std::string& geometry,
                       int geometry_components, const std::vector<XdmfField>& fields) {
  const std::string grid = detail::xdmf_grid(h5.filename().string(), n, time, geometry, geometry_components, fields);
  auto xmf = h5;
  xmf.replace_extension(".xmf");
  write_text_file(xmf, detail::xdmf_document(grid));
  // the series: each snapshot's grid, read back from its own description
  std::vector<std::filesystem::path> parts;
  for (const auto& e : std::filesystem::directory_iterator(h5.parent_path().empty() ? "." : h5.parent_path())) {
    const std::string name = e.path().filename().string();
    if (name.rfind("snap_", 0) == 0 && e.path().extension() == ".xmf") parts.push_back(e.path());
  }
  std::sort(parts.begin(), parts.end());
  std::string series = "    <Grid Name=\"series\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (const auto& part : parts) {
    const std::string text = read_text_file(part);
    const auto a = text.find("    <Grid Name=\"particles\"");
    const auto b = text.find("    </Grid>\n", a);
    if (a == std::string::npos || b == std::string::npos) continue;
    std::string grid_text = text.substr(a, b + 12 - a);
    const auto c = grid_text.find("<!-- time ");
    const auto c_end = grid_text.find(" -->", c);
    if (c != std::string::npos && c_end != std::string::npos)
      grid_text.replace(c, c_end + 4 - c, "<Time Value=\"" + grid_text.substr(c + 10, c_end - c - 10) + "\"/>");
    series += grid_text;
  }
  write_text_file(h5.parent_path() / "snapshots.xmf", detail::xdmf_document(series + "    </Grid>\n"));
}

}  // namespace rsph::io
