// The IDL message types under C++ names (heslam::msg::StereoFrame = heslam_msg_StereoFrame) and the
// compile-time traits the typed Topic/Writer/Reader need (topic descriptor, type name).
#pragma once

#include <dds/dds.h>

#include "idl/camera.h"
#include "idl/common.h"
#include "idl/imu.h"
#include "idl/lockstep.h"
#include "idl/loop.h"
#include "idl/map.h"
#include "idl/occupancy.h"
#include "idl/occupancy_save.h"
#include "idl/odometry.h"
#include "idl/status.h"

namespace heslam::msg {

// This build's message schema; every topic type carries it in its schema_version field.
inline constexpr uint32_t kSchemaVersion = heslam_msg_SCHEMA_VERSION;

using Pose = heslam_msg_Pose;
using RectifiedStereoCamera = heslam_msg_RectifiedStereoCamera;
using StereoFrame = heslam_msg_StereoFrame;
using CameraModel = heslam_msg_CameraModel;
using ExplicitRectification = heslam_msg_ExplicitRectification;
using StereoCalibration = heslam_msg_StereoCalibration;
using ImuReading = heslam_msg_ImuReading;
using ImuBatch = heslam_msg_ImuBatch;
using ImuCalibration = heslam_msg_ImuCalibration;
using StageTime = heslam_msg_StageTime;
using Odometry = heslam_msg_Odometry;
using KeyframeKeypoint = heslam_msg_KeyframeKeypoint;
using NewStereoPoint = heslam_msg_NewStereoPoint;
using Keyframe = heslam_msg_Keyframe;
using CovisibleKeyframe = heslam_msg_CovisibleKeyframe;
using KeyframeState = heslam_msg_KeyframeState;
using PointObservation = heslam_msg_PointObservation;
using MapPointState = heslam_msg_MapPointState;
using CorrectedKeyframePose = heslam_msg_CorrectedKeyframePose;
using PointMerge = heslam_msg_PointMerge;
using CorrectedPointPosition = heslam_msg_CorrectedPointPosition;
using LoopCorrection = heslam_msg_LoopCorrection;
using FrameDone = heslam_msg_FrameDone;
using KeyframeDone = heslam_msg_KeyframeDone;
using StageStats = heslam_msg_StageStats;
using Counter = heslam_msg_Counter;
using ComponentStatus = heslam_msg_ComponentStatus;
using OccupancyGrid2D = heslam_msg_OccupancyGrid2D;
using DenseCloud = heslam_msg_DenseCloud;
using OccupancySaveRequest = heslam_msg_OccupancySaveRequest;
using OccupancySaveReply = heslam_msg_OccupancySaveReply;

}  // namespace heslam::msg

namespace heslam::runtime {

// Specialised below for every topic type; using any other type with Writer/Reader fails to compile.
template <typename T>
struct MessageTraits;

#define HESLAM_RUNTIME_MESSAGE(TYPE, NAME)                                     \
  template <>                                                                  \
  struct MessageTraits<TYPE> {                                                 \
    static const dds_topic_descriptor_t* descriptor() { return &TYPE##_desc; } \
    static constexpr const char* name() { return NAME; }                       \
  }

HESLAM_RUNTIME_MESSAGE(heslam_msg_StereoFrame, "StereoFrame");
HESLAM_RUNTIME_MESSAGE(heslam_msg_StereoCalibration, "StereoCalibration");
HESLAM_RUNTIME_MESSAGE(heslam_msg_ImuBatch, "ImuBatch");
HESLAM_RUNTIME_MESSAGE(heslam_msg_ImuCalibration, "ImuCalibration");
HESLAM_RUNTIME_MESSAGE(heslam_msg_Odometry, "Odometry");
HESLAM_RUNTIME_MESSAGE(heslam_msg_Keyframe, "Keyframe");
HESLAM_RUNTIME_MESSAGE(heslam_msg_KeyframeState, "KeyframeState");
HESLAM_RUNTIME_MESSAGE(heslam_msg_MapPointState, "MapPointState");
HESLAM_RUNTIME_MESSAGE(heslam_msg_LoopCorrection, "LoopCorrection");
HESLAM_RUNTIME_MESSAGE(heslam_msg_FrameDone, "FrameDone");
HESLAM_RUNTIME_MESSAGE(heslam_msg_KeyframeDone, "KeyframeDone");
HESLAM_RUNTIME_MESSAGE(heslam_msg_ComponentStatus, "ComponentStatus");
HESLAM_RUNTIME_MESSAGE(heslam_msg_OccupancyGrid2D, "OccupancyGrid2D");
HESLAM_RUNTIME_MESSAGE(heslam_msg_DenseCloud, "DenseCloud");
HESLAM_RUNTIME_MESSAGE(heslam_msg_OccupancySaveRequest, "OccupancySaveRequest");
HESLAM_RUNTIME_MESSAGE(heslam_msg_OccupancySaveReply, "OccupancySaveReply");

#undef HESLAM_RUNTIME_MESSAGE

template <typename T>
concept Message = requires(T sample) {
  {MessageTraits<T>::descriptor()};
  {sample.schema_version};
};

}  // namespace heslam::runtime
