#include "records.hpp"

#include <cstddef>
#include <type_traits>

namespace cstreams::python {

namespace {

struct Field {
  const char* name;
  const char* format;
  std::size_t offset;
};

py::dtype structured(std::initializer_list<Field> fields, std::size_t itemsize)
{
  py::list names, formats, offsets;
  for (const Field& f : fields) {
    names.append(f.name);
    formats.append(f.format);
    offsets.append(f.offset);
  }
  py::dict spec;
  spec["names"] = names;
  spec["formats"] = formats;
  spec["offsets"] = offsets;
  spec["itemsize"] = itemsize;
  return py::dtype::from_args(spec);
}

static_assert(std::is_standard_layout_v<Contact> && std::is_standard_layout_v<ClosePair>);
static_assert(sizeof(ContactKind) == 1 && sizeof(float) == 4);

}  // namespace

py::dtype contact_dtype()
{
  return structured({{"kind", "u1", offsetof(Contact, kind)},
                     {"object_a", "u4", offsetof(Contact, object_a)},
                     {"object_b", "u4", offsetof(Contact, object_b)},
                     {"v", "(4,)u4", offsetof(Contact, v)},
                     {"toi", "f8", offsetof(Contact, toi)}},
                    sizeof(Contact));
}

py::dtype close_pair_dtype()
{
  return structured({{"kind", "u1", offsetof(ClosePair, kind)},
                     {"object_a", "u4", offsetof(ClosePair, object_a)},
                     {"object_b", "u4", offsetof(ClosePair, object_b)},
                     {"a", "u4", offsetof(ClosePair, a)},
                     {"b", "u4", offsetof(ClosePair, b)},
                     {"v", "(4,)u4", offsetof(ClosePair, v)},
                     {"type", "u1", offsetof(ClosePair, type)},
                     {"distance", "f4", offsetof(ClosePair, distance)}},
                    sizeof(ClosePair));
}

py::dict stats_dict(const DetectorStats& s)
{
  py::dict out;
  out["host_ms"] = s.host_ms;
  out["device_ms"] = double(s.device_ns()) * 1e-6;
  out["peak_bytes"] = s.peak_bytes;
  out["front_pairs"] = s.front_pairs;
  out["triangle_pairs"] = s.triangle_pairs;
  out["vf_candidates"] = s.vf_candidates;
  out["ee_candidates"] = s.ee_candidates;
  out["contacts"] = s.contacts;
  out["launches"] = s.launches;
  return out;
}

}  // namespace cstreams::python
