// The list of GI techniques. Add one line per technique.
#include "gi/technique.h"
#include "gi/vpl/techniques.h"
#include "gi/rsm/rsm_technique.h"
#include "gi/splat/splat_technique.h"
#include "gi/sh_igi/sh_igi_technique.h"
#include "gi/lpv/lpv_technique.h"
#include "gi/vct/vct_technique.h"
#include "gi/ssao/ssao_technique.h"
#include "gi/probes/probes_technique.h"
#include "gi/second_order/second_order.h"

namespace gi {

const std::vector<TechniqueInfo>& techniqueRegistry() {
  static const std::vector<TechniqueInfo> registry = {
      vplTechniqueInfo(),
      igiTechniqueInfo(),
      rsmTechniqueInfo(),
      splatTechniqueInfo(),
      shIgiTechniqueInfo(),
      lpvTechniqueInfo(),
      vctTechniqueInfo(),
      ssaoTechniqueInfo(),
      probesTechniqueInfo(),
      secondOrderTechniqueInfo(),
  };
  return registry;
}

const TechniqueInfo* findTechnique(const std::string& name) {
  for (const TechniqueInfo& t : techniqueRegistry())
    if (t.name == name) return &t;
  return nullptr;
}

}  // namespace gi
