#pragma once
// What a client may do by its role, for the interfaces that know a client by its certificate
// (Modbus/TCP Security; HTTPS with a client certificate): read, operate (setpoints, mode, records,
// jog, halt, reset: every point of write access) or tune (the tuning and the services besides, with
// no unlock). The configuration maps each role name to one of them; the gate enforces the result
// as it enforces every other client's (Requester), so the rule is the same on every interface.
#include <array>
#include <optional>
#include <string>
#include <string_view>

#include "points/write_gate.hpp"

namespace epa::points {

enum class Rights : std::uint8_t { kRead, kOperate, kTune };
inline constexpr std::array<std::string_view, 3> kRightsNames = {"read", "operate", "tune"};

inline std::string_view to_string(Rights r) { return kRightsNames[static_cast<std::size_t>(r)]; }
inline std::optional<Rights> parse_rights(std::string_view text) {
  for (std::size_t i = 0; i < kRightsNames.size(); ++i)
    if (kRightsNames[i] == text) return static_cast<Rights>(i);
  return std::nullopt;
}

// The requester for a client with `rights` by the `role` its certificate of `subject` names;
// `source` names it in the audit trail.
inline Requester requester_with_rights(std::string source, std::string_view subject, std::string_view role, Rights rights) {
  Requester who{std::move(source), rights != Rights::kRead, "", rights == Rights::kTune};
  const std::string quoted_role = "certificate " + std::string(subject) + ": role \"" + std::string(role) + "\"";
  if (rights == Rights::kRead) who.no_write_reason = quoted_role + " has read rights only";
  if (rights == Rights::kOperate) who.tuning_locked_reason = quoted_role + " has no tuning rights";
  return who;
}

}  // namespace epa::points
