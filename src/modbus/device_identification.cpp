#include "modbus/device_identification.hpp"

#include <algorithm>
#include <filesystem>
#include <string>

#include "core/version.hpp"
#include "modbus/exception_codes.hpp"

namespace epa::modbus {

namespace {

constexpr std::uint8_t kFunction = 0x2B;
constexpr std::uint8_t kConformity = 0x82;  // regular identification, stream and individual access
constexpr std::uint8_t kBasic = 1, kIndividual = 4;  // 2 regular, 3 extended
constexpr std::uint8_t kLastBasic = 0x02, kLastRegular = 0x06;

std::string_view object_value(const DeviceIdentity& identity, int id) {
  const std::string& v = identity.objects[static_cast<std::size_t>(id)];
  return std::string_view(v).substr(0, DeviceIdentity::kMaxObjectBytes);
}

void append_object(std::vector<std::uint8_t>& pdu, int id, std::string_view value) {
  pdu.push_back(static_cast<std::uint8_t>(id));
  pdu.push_back(static_cast<std::uint8_t>(value.size()));
  pdu.insert(pdu.end(), value.begin(), value.end());
}

}  // namespace

std::string status_page_url(std::string_view web_port) { return "http://" + std::string(kHostPlaceholder) + ":" + std::string(web_port) + "/"; }

std::string status_page_url(int web_port) { return status_page_url(std::to_string(web_port)); }

DeviceIdentity with_host(DeviceIdentity identity, std::string_view host) {
  std::string& url = identity.objects[3];
  if (const auto at = url.find(kHostPlaceholder); at != std::string::npos) url.replace(at, kHostPlaceholder.size(), host);
  return identity;
}

DeviceIdentity appliance_identity(std::string_view register_map_path, std::string_view status_page_url) {
  return {{"EPA project", "epa", std::string(core::kVersion),
           // No public project address exists yet: the appliance's own status page, where its documentation
           // for the integrator lives (docs/http-api.md).
           std::string(status_page_url), "EPA electro-pneumatic axis controller", "epa appliance",
           std::filesystem::path(register_map_path).filename().string()}};
}

std::uint8_t read_device_identification(const std::uint8_t* data, int length, const DeviceIdentity& identity,
                                        std::vector<std::uint8_t>& pdu) {
  if (length >= 1 && data[0] != kMeiDeviceIdentification) return kIllegalFunction;  // CANopen (0x0D) or another MEI
  if (length != 3) return kIllegalValue;
  const std::uint8_t code = data[1];
  const int object = data[2];
  if (code < kBasic || code > kIndividual) return kIllegalValue;
  if (code == kIndividual && object > kLastRegular) return kIllegalAddress;

  // Function, MEI type, read code, conformity level, more follows, next object id, number of objects.
  pdu.assign({kFunction, kMeiDeviceIdentification, code, kConformity, 0x00, 0x00, 0x00});
  if (code == kIndividual) {
    append_object(pdu, object, object_value(identity, object));
    pdu[6] = 1;
    return 0;
  }
  // Stream access: from `object` to the last object of the level asked for (extended is answered
  // as regular: this device has no extended objects), as many whole objects as the PDU holds.
  const int last = code == kBasic ? kLastBasic : kLastRegular;
  const int first = object <= last ? object : 0;  // an id it does not have: from the start
  int count = 0;
  for (int id = first; id <= last; ++id) {
    const std::string_view value = object_value(identity, id);
    if (pdu.size() + 2 + value.size() > static_cast<std::size_t>(kMaxPduBytes)) {
      pdu[4] = 0xFF;  // more follows: the client asks again from `id`
      pdu[5] = static_cast<std::uint8_t>(id);
      break;
    }
    append_object(pdu, id, value);
    ++count;
  }
  pdu[6] = static_cast<std::uint8_t>(count);
  return 0;
}

}  // namespace epa::modbus
