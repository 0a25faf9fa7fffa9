#pragma once
// The positioning interface's two words, bit by bit (docs/registers.md lists them): the control
// word a client writes (also as single coils) and the status word it reads (also as single
// discrete inputs). Bit numbers are part of the Modbus interface: append, never renumber.
#include <cstdint>

namespace epa::runtime {

// Control word bits.
enum ControlBit : std::uint16_t {
  kControlStart = 1u << 0,     // rising edge: start the selected record (0: the setpoint); needs RUN
  kControlHalt = 1u << 1,      // rising edge: brake and hold where the piston stops
  kControlJogPlus = 1u << 2,   // held: jog towards larger positions (MANUAL); released: brake
  kControlJogMinus = 1u << 3,  // held: jog towards smaller positions (MANUAL)
  kControlReset = 1u << 4,     // rising edge: clear a latched fault
};
inline constexpr std::uint16_t kControlWordMask = 0x1F;
inline constexpr int kControlBits = 5;

// Status word bit numbers.
enum StatusBit : int {
  kStatusReady = 0,           // no fault latched and the I/O works: the axis can be enabled
  kStatusEnabled = 1,         // mode RUN: the control law holds or moves the axis
  kStatusMoving = 2,          // a move, halt or jog is under way
  kStatusInPosition = 3,      // |target - position| <= the window for the in-position time (RUN)
  kStatusTargetReached = 4,   // the last started move came into position (cleared by the next start)
  kStatusFollowingError = 5,  // |reference - position| beyond following_error_mm now (the fault follows after its time)
  kStatusWarning = 6,         // following error, off target, I/O errors, the store not saving or its disk low: look before it faults
  kStatusFault = 7,           // a fault is latched (fault_code says which)
  kStatusAck = 8,             // mirrors the control word's start bit once the loop applied it (handshake)
  kStatusHalted = 9,          // the last task was a halt
  kStatusJogging = 10,        // a jog (or its braking) is under way
  kStatusManual = 11,         // mode MANUAL
  kStatusOffTarget = 12,      // the move stopped outside its window: the piston stands there (also a warning)
  kStatusHunting = 13,        // a limit cycle about the standing target: the valve is held centred until the next target (also a warning)
  kStatusHealthWarning = 14,  // the model-health monitor finds the axis drifted from its model, or hunting (also a warning; never a fault)
};
inline constexpr int kStatusBits = 15;

}  // namespace epa::runtime
