// The answers to reads built without libmodbus (read_answer.hpp), judged against libmodbus' own
// modbus_reply on the same image and request: every byte the same, over many random reads.
#include <gtest/gtest.h>
#include <modbus.h>
#include <sys/socket.h>
#include <unistd.h>

#include <random>
#include <vector>

#include "modbus/read_answer.hpp"

namespace epa::modbus {
namespace {

using Bytes = std::vector<std::uint8_t>;

// libmodbus' answer to the ADU `request`, written into a socket pair and read back, without MBAP.
Bytes libmodbus_answer(modbus_t* ctx, const Bytes& request, modbus_mapping_t* image) {
  int fds[2];
  EXPECT_EQ(socketpair(AF_UNIX, SOCK_STREAM, 0, fds), 0);
  modbus_set_socket(ctx, fds[0]);
  EXPECT_GT(modbus_reply(ctx, request.data(), static_cast<int>(request.size()), image), 0);
  Bytes adu(MODBUS_TCP_MAX_ADU_LENGTH);
  const ssize_t n = recv(fds[1], adu.data(), adu.size(), 0);
  ::close(fds[0]);
  ::close(fds[1]);
  EXPECT_GT(n, 7);
  return Bytes(adu.begin() + 7, adu.begin() + n);
}

TEST(ReadAnswer, EveryReadIsAnsweredAsLibmodbusAnswersIt) {
  modbus_t* ctx = modbus_new_tcp(nullptr, 502);
  modbus_mapping_t* image = modbus_mapping_new_start_address(0, 300, 0, 40, 0, 1200, 0, 500);
  ASSERT_NE(image, nullptr);
  std::mt19937 random(7);
  for (int i = 0; i < 300; ++i) image->tab_bits[i] = random() & 1;
  for (int i = 0; i < 40; ++i) image->tab_input_bits[i] = random() & 1;
  for (int i = 0; i < 1200; ++i) image->tab_registers[i] = static_cast<std::uint16_t>(random());
  for (int i = 0; i < 500; ++i) image->tab_input_registers[i] = static_cast<std::uint16_t>(random());
  const struct {
    int fc, size, max;
  } tables[] = {{1, 300, MODBUS_MAX_READ_BITS}, {2, 40, MODBUS_MAX_READ_BITS}, {3, 1200, MODBUS_MAX_READ_REGISTERS}, {4, 500, MODBUS_MAX_READ_REGISTERS}};
  int compared = 0;
  for (const auto& t : tables) {
    for (int n = 0; n < 200; ++n) {
      const int quantity = 1 + static_cast<int>(random() % static_cast<unsigned>(std::min(t.max, t.size)));
      const int address = static_cast<int>(random() % static_cast<unsigned>(t.size - quantity + 1));
      const Bytes pdu = {static_cast<std::uint8_t>(t.fc), static_cast<std::uint8_t>(address >> 8), static_cast<std::uint8_t>(address),
                         static_cast<std::uint8_t>(quantity >> 8), static_cast<std::uint8_t>(quantity)};
      Bytes adu = {0x12, 0x34, 0, 0, 0, static_cast<std::uint8_t>(pdu.size() + 1), 1};
      adu.insert(adu.end(), pdu.begin(), pdu.end());
      const auto ours = read_answer(pdu.data(), static_cast<int>(pdu.size()), image);
      ASSERT_TRUE(ours) << "fc " << t.fc << " address " << address << " quantity " << quantity;
      EXPECT_EQ(*ours, libmodbus_answer(ctx, adu, image)) << "fc " << t.fc << " address " << address << " quantity " << quantity;
      ++compared;
    }
  }
  EXPECT_EQ(compared, 800);
  modbus_mapping_free(image);
  modbus_free(ctx);
}

TEST(ReadAnswer, AnythingButAReadInsideTheImageIsLeftToLibmodbus) {
  modbus_mapping_t* image = modbus_mapping_new_start_address(0, 16, 0, 16, 0, 100, 0, 100);
  const Bytes write = {0x06, 0x00, 0x01, 0x00, 0x05}, beyond = {0x03, 0x00, 0x60, 0x00, 0x05}, none = {0x03, 0x00, 0x00, 0x00, 0x00},
              too_many = {0x03, 0x00, 0x00, 0x00, 0x7E}, short_pdu = {0x03, 0x00, 0x00};
  for (const Bytes& pdu : {write, beyond, none, too_many, short_pdu})
    EXPECT_FALSE(read_answer(pdu.data(), static_cast<int>(pdu.size()), image)) << int(pdu[0]);
  modbus_mapping_free(image);
}

}  // namespace
}  // namespace epa::modbus
