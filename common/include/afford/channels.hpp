// Channel names of a run. Runs are isolated by LCM URL (one UDP port per run),
// so names are plain. See docs/processes-and-channels.md for who publishes what.
#pragma once

namespace afford::channel {
inline constexpr const char* kRunConfig = "RUN_CONFIG";
inline constexpr const char* kRunControl = "RUN_CONTROL";
inline constexpr const char* kStatus = "STATUS";
inline constexpr const char* kScene = "SCENE";
inline constexpr const char* kFocus = "FOCUS";
inline constexpr const char* kPrediction = "PREDICTION";
inline constexpr const char* kDecision = "DECISION";
inline constexpr const char* kEffect = "EFFECT";
inline constexpr const char* kProbe = "PROBE";
inline constexpr const char* kAffordanceTable = "AFFORDANCE_TABLE";
inline constexpr const char* kResult = "RESULT";
inline constexpr const char* kLook = "LOOK";
inline constexpr const char* kForwardQuery = "FORWARD_QUERY";
inline constexpr const char* kForwardPrediction = "FORWARD_PREDICTION";
inline constexpr const char* kExtrinsicResult = "EXTRINSIC_RESULT";
inline constexpr const char* kResend = "RESEND";

// The channels whose messages carry a serial: every run message except the
// runner's (RUN_CONFIG, RUN_CONTROL) and the wall-clock ones (STATUS, RESEND).
inline constexpr const char* kWithSerial[] = {kScene,  kFocus,           kPrediction, kDecision,
                                              kEffect, kProbe,           kAffordanceTable, kResult,
                                              kLook,   kForwardQuery,    kForwardPrediction, kExtrinsicResult};

// Every channel of a run (the most a STATUS lists).
inline constexpr const char* kAll[] = {kRunConfig, kRunControl, kStatus, kScene, kFocus, kPrediction,
                                       kDecision, kEffect, kProbe, kAffordanceTable, kResult, kLook,
                                       kForwardQuery, kForwardPrediction, kExtrinsicResult, kResend};
}  // namespace afford::channel
