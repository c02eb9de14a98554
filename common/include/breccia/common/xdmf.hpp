#pragma once
// The XDMF 3 elements of the sidecars ParaView opens beside an HDF5 file (particles.xdmf
// of particle_file.cpp, results.xdmf of solver/src/results_layout.cpp): written here once,
// so both files spell the elements, number types and HDF references the same way. Each
// caller lays its elements out (indentation, line breaks), which keeps their files as they
// were.
#include <cstddef>
#include <string>

namespace breccia {

// <?xml ...?><Xdmf Version="3.0"><Domain> and the matching close, each with its line breaks.
std::string xdmf_document_begin();
std::string xdmf_document_end();

// <DataItem Dimensions="dims" NumberType="Float|Int" Precision="p" Format="HDF">source</DataItem>;
// source is "file.h5:/dataset".
std::string xdmf_data_item(const std::string& dimensions, bool integer, int precision, const std::string& source);
// "n" for one value per point, "n k" for k components.
std::string xdmf_dimensions(size_t n, int components = 1);

// <Topology TopologyType="Polyvertex" NumberOfElements="n" NodesPerElement="1"/>: one vertex per particle.
std::string xdmf_polyvertex_topology(size_t n);

// The opening tag <Attribute Name="name" AttributeType="type" Center="center">; type from
// xdmf_attribute_type (Scalar, Vector for 3 components, Tensor6 for 6).
std::string xdmf_attribute_begin(const std::string& name, const char* type, const char* center);
const char* xdmf_attribute_type(int components);

}  // namespace breccia
