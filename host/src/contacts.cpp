#include <cstreams/contacts.hpp>
#include <cstreams/io/file_output.hpp>

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cstdio>
#include <ostream>
#include <tuple>

namespace cstreams {

bool canonical_less(const Contact& a, const Contact& b)
{
  return std::tie(a.kind, a.object_a, a.object_b, a.v, a.toi) < std::tie(b.kind, b.object_a, b.object_b, b.v, b.toi);
}

// Lists of 10^5 contacts take milliseconds to sort on one core: longer than the
// device takes to find them.
void sort_canonical(std::vector<Contact>& contacts)
{
  tbb::parallel_sort(contacts.begin(), contacts.end(), canonical_less);
}

void write_contacts_csv(std::ostream& out, ContactSpan contacts)
{
  out << "kind,object_a,object_b,v0,v1,v2,v3,toi\n";
  char row[160];
  for (const auto& c : contacts) {
    std::snprintf(row, sizeof row, "%s,%u,%u,%u,%u,%u,%u,%.17g\n", c.kind == ContactKind::vertex_face ? "vf" : "ee",
                  c.object_a, c.object_b, c.v[0], c.v[1], c.v[2], c.v[3], c.toi);
    out << row;
  }
}

void write_contacts_csv(const std::string& path, ContactSpan contacts)
{
  write_file_atomically(path, [&](std::ostream& out) { write_contacts_csv(out, contacts); });
}

}  // namespace cstreams
