#pragma once
// The typed names of the appliance's points. Code refers to a point by its PointId; its public
// name (the register map's `name` column, the JSON API's keys, the audit trail, the store's
// retained points) is written once, in point_catalog.cpp.
#include <cstddef>
#include <cstdint>

#include "control/rst_law.hpp"
#include "runtime/axis_words.hpp"

namespace epa::points {

inline constexpr std::size_t kCoefficients = control::kMaxLawOrder + 1;  // F0..F6, G0..G6, H0..H6
inline constexpr std::size_t kPositionRecords = 32;  // record 1..32 of the position-record table
inline constexpr std::size_t kFaultHistoryPoints = 8;  // the newest faults an HMI reads, 0 the newest

enum class PointId : std::uint16_t {
  // identity and status
  kVersionMajor, kVersionMinor, kVersionPatch, kMode, kFaultCode, kFaultActive, kController,
  kSetpoint, kPosition, kError, kSensor, kValve, kControllerOutput, kManualValve, kSaturated, kIoOk,
  // commands
  kReset, kHeartbeat, kRecord, kUnlock,
  // the positioning interface: control word (and its bits as coils), the record a start takes,
  // status word (and its bits as discrete inputs), the law's reference, the measured speed
  kControlWord, kRecordSelect, kControlBit0,
  kStatusWord = kControlBit0 + runtime::kControlBits, kStatusBit0,
  kReference = kStatusBit0 + runtime::kStatusBits, kSpeed,
  // the limits and windows the configuration (and the register map) set, for an HMI to read
  kConfiguredSoftMin, kConfiguredSoftMax, kConfiguredSetpointMin, kConfiguredSetpointMax, kConfiguredInPositionWindow,
  kConfiguredFollowingError, kConfiguredFollowingTime, kRunningController,
  // the interfaces and the store
  kLocked, kStoreOk, kDiskLow, kChangeCounter, kSavedCounter, kModbusRequests, kModbusClients, kUnlockFailures,
  // tuning
  kTs, kMr, kMl, kBr, kBl, kLc, kTrajSpeedFraction, kTrajBandwidth, kTrajHoldBand,
  // the excitation experiment (mode EXCITE)
  kExciteSeed, kExciteAmplitudeMin, kExciteAmplitudeMax, kExciteDuration, kExciteLeft,
  // the commissioning service: its command (start, abort) and state
  kCommissionCommand, kCommissionStage, kCommissionVerdict, kCommissionProgress,
  // the model-health monitor: its command (retake the baseline) and verdict
  kHealthCommand, kHealthState, kHealthEffect, kHealthValue, kHealthCommissioned, kHealthRatio, kHealthMovesSinceOnset, kHealthMovesSeen,
  // the last move
  kMoveNumber, kMoveFrom, kMoveTo, kMoveRise, kMoveSettling, kMoveEss, kMoveOvershoot, kMoveEnd,
  // loop statistics and counters
  kLoopWakeP50, kLoopWakeP99, kLoopWakeMax, kLoopJitterP99, kLoopComputeP99, kLoopOverruns, kCycles, kUptime,
  kMoves, kFaults, kIoErrors, kCommandsApplied, kCommandsRejected, kLastCommandRefusal,
  // the fault history: how many, then the newest kFaultHistoryPoints, kFaultCode0 + i ... for entry i
  kFaultHistoryCount,
  kFaultCode0,
  kFaultMode0 = kFaultCode0 + kFaultHistoryPoints,
  kFaultTime0 = kFaultMode0 + kFaultHistoryPoints,
  kFaultPosition0 = kFaultTime0 + kFaultHistoryPoints,
  kFaultSetpoint0 = kFaultPosition0 + kFaultHistoryPoints,
  kFaultValve0 = kFaultSetpoint0 + kFaultHistoryPoints,
  // the position-record table: kRecordTarget0 + i ... for record i + 1, i < kPositionRecords
  kRecordTarget0 = kFaultValve0 + kFaultHistoryPoints,
  kRecordSpeed0 = kRecordTarget0 + kPositionRecords,
  kRecordWindow0 = kRecordSpeed0 + kPositionRecords,
  kRecordController0 = kRecordWindow0 + kPositionRecords,
  kRecordApproach0 = kRecordController0 + kPositionRecords,
  // controller coefficients: kF0 + i, kG0 + i, kH0 + i for i < kCoefficients
  kF0 = kRecordApproach0 + kPositionRecords,
  kG0 = kF0 + kCoefficients,
  kH0 = kG0 + kCoefficients,
  kCount = kH0 + kCoefficients,
};

inline constexpr std::size_t kPointCount = static_cast<std::size_t>(PointId::kCount);
inline constexpr std::size_t index(PointId id) { return static_cast<std::size_t>(id); }
inline constexpr PointId indexed_id(PointId first, std::size_t i) {
  return static_cast<PointId>(static_cast<std::size_t>(first) + i);
}
// The control-word bit a coil point stands for (kControlBit0 + bit), or -1 for any other point.
inline constexpr int control_bit(PointId id) {
  const std::size_t bit = index(id) - index(PointId::kControlBit0);  // wraps for ids below: not a bit
  return bit < static_cast<std::size_t>(runtime::kControlBits) ? static_cast<int>(bit) : -1;
}
// kFaultCode0 + i and the like: the same arithmetic.
inline constexpr PointId fault_history_id(PointId first, std::size_t i) { return indexed_id(first, i); }

}  // namespace epa::points
