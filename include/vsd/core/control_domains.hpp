#pragma once
// Which parts of driving a controller takes over from the Ego's: speed (longitudinal),
// steering (lateral) or both - OpenSCENARIO's ActivateControllerAction longitudinal / lateral.

namespace vsd {

enum class ControlDomains { Both, Longitudinal, Lateral };

/// True if `domains` includes `domain` (Longitudinal or Lateral).
constexpr bool drives(ControlDomains domains, ControlDomains domain) {
  return domains == ControlDomains::Both || domains == domain;
}

}  // namespace vsd
