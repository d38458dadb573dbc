#include "tetrapage/tools/ContactFile.h"

#include "tetrapage/tools/AnswerSite.h"

namespace tetrapage {

ContactFile::ContactFile(const std::filesystem::path& path, const CollisionIndex& index)
    : file_(path, std::string("step,") + kAnswerSiteHeader), index_(index) {}

void ContactFile::write_step(std::uint64_t step, FlyingObject& object, const QueryResult& result) {
  const std::string prefix = std::to_string(step) + ',';
  if (result.containment != Containment::none)
    file_.row(prefix + site_fields(containment_site(result.containment, result.containing_part,
                                                    result.containing_dynamic_part),
                                   index_, object));
  for (const Contact& contact : result.contacts)
    file_.row(prefix + site_fields(contact_site(object, contact), index_, object));
}

}  // namespace tetrapage
