#pragma once
// Function 43 / MEI type 14 (0x2B / 0x0E), Read Device Identification, as the Modbus Application
// Protocol Specification v1.1b3 section 6.21 describes it. libmodbus' modbus_reply answers FC43
// with exception 01, so the response PDU is built here, without sockets.
//
// Conformity level 0x82: the basic (0x00-0x02) and regular (0x03-0x06) objects, by stream (read
// codes 01 basic, 02 regular, 03 extended) and one at a time (code 04). There are no extended
// objects, so code 03 is answered at the regular level, as the spec asks of a request above the
// device's level. A stream that does not fit the 253-byte PDU ends with "more follows" (0xFF) and
// the next object's id, which the client sends back in its next request.
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace epa::modbus {

inline constexpr std::uint8_t kMeiDeviceIdentification = 0x0E;
inline constexpr int kMaxPduBytes = 253;  // a Modbus PDU, function code included (MODBUS_MAX_PDU_LENGTH)

struct DeviceIdentity {
  // Objects 0x00-0x06 by id: VendorName, ProductCode, MajorMinorRevision, VendorUrl, ProductName,
  // ModelName, UserApplicationName. Each is sent whole (an object is indivisible): at most
  // kMaxObjectBytes, longer ones are cut there.
  std::array<std::string, 7> objects;
  static constexpr int kMaxObjectBytes = kMaxPduBytes - 7 - 2;  // the response's own 7 bytes, the object's id and length
};

// The address of the appliance's status page served on `web_port`, as VendorUrl names it, with
// the host as a placeholder: each request's answer puts in the address its client reached the
// appliance at (with_host), which names it on that client's network.
inline constexpr std::string_view kHostPlaceholder = "<appliance>";
std::string status_page_url(int web_port);
// The same with the port given as text: the register document writes "<[web] port>", since the
// port is a setting of the web server, which this layer does not see.
std::string status_page_url(std::string_view web_port);

// This appliance's objects: the version of project() in CMakeLists.txt as the revision,
// `status_page_url` (status_page_url(), or "" with no status page) as the vendor's URL, and
// `register_map_path`'s file name as the user application (the map is what a site configures).
DeviceIdentity appliance_identity(std::string_view register_map_path, std::string_view status_page_url);
// `identity` with the status page's host placeholder replaced by `host`: the address a client
// reached this appliance at, which it can reach the status page at too.
DeviceIdentity with_host(DeviceIdentity identity, std::string_view host);

// `data` is the request PDU after the function code (MEI type, read code, object id), `length`
// bytes. Returns 0 with the whole response PDU (function code first) in `pdu`, or the exception:
// 01 another MEI type; 03 a read code other than 01-04, or a request not 3 bytes long;
// 02 an object id this device does not have, asked for individually (code 04). A stream request
// (codes 01-03) for an id it does not have starts from object 0, as the spec says.
std::uint8_t read_device_identification(const std::uint8_t* data, int length, const DeviceIdentity& identity,
                                        std::vector<std::uint8_t>& pdu);

}  // namespace epa::modbus
