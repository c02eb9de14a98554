#include "breccia/common/xdmf.hpp"

namespace breccia {

std::string xdmf_document_begin() { return "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n"; }

std::string xdmf_document_end() { return " </Domain>\n</Xdmf>\n"; }

namespace {
// XML's five reserved characters as entities: a file name with & or < in it made a sidecar
// no XML parser reads.
std::string xml_escaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&apos;"; break;
      default: out += c;
    }
  }
  return out;
}
}  // namespace

std::string xdmf_data_item(const std::string& dimensions, bool integer, int precision, const std::string& source) {
  return "<DataItem Dimensions=\"" + dimensions + "\" NumberType=\"" + (integer ? "Int" : "Float") + "\" Precision=\"" +
         std::to_string(precision) + "\" Format=\"HDF\">" + xml_escaped(source) + "</DataItem>";
}

std::string xdmf_dimensions(size_t n, int components) {
  std::string d = std::to_string(n);
  if (components > 1) d += ' ' + std::to_string(components);
  return d;
}

std::string xdmf_polyvertex_topology(size_t n) {
  return "<Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" + std::to_string(n) + "\" NodesPerElement=\"1\"/>";
}

std::string xdmf_attribute_begin(const std::string& name, const char* type, const char* center) {
  return "<Attribute Name=\"" + name + "\" AttributeType=\"" + type + "\" Center=\"" + center + "\">";
}

const char* xdmf_attribute_type(int components) {
  return components == 3 ? "Vector" : components == 6 ? "Tensor6" : "Scalar";
}

}  // namespace breccia
