// Generator of the CCL reference packets in ccl_bytes.rs (see that file for how it is built
// and run). Links against an unmodified build of the CIGI Class Library (LGPL).
// Dumps reference packets packed by the CIGI Class Library, in the build's native byte order.
#include <cstdio>
#include <cstring>
#include "CigiAllPackets.h"
#include "CigiVersionID.h"
#include "CigiAnimationTable.h"

static void dump(const char *name, Cigi_uint8 *b, int n) {
  printf("%s ", name);
  for (int i = 0; i < n; i++) printf("%02x", b[i]);
  printf("\n");
}

template <class T> static void pack(const char *name, T &p, void *spec) {
  Cigi_uint8 buf[256];
  memset(buf, 0xEE, sizeof buf);
  int n = p.Pack(&p, buf, spec);
  dump(name, buf, n);
}

#define IGC(CLS) struct CLS##X : CLS { void fill() { \
  DatabaseID = -3; IGMode = (decltype(IGMode))2; TimestampValid = true; \
  FrameCntr = 0x01020304; TimeStampV3 = 123456; LastRcvdIGFrame = 0xA0B0C0D0; fill2(); } void fill2(); };
IGC(CigiIGCtrlV3) void CigiIGCtrlV3X::fill2() {}
IGC(CigiIGCtrlV3_2) void CigiIGCtrlV3_2X::fill2() {}
IGC(CigiIGCtrlV3_3) void CigiIGCtrlV3_3X::fill2() { SmoothingEn = true; }

#define SOF(CLS) struct CLS##X : CLS { void fill() { \
  DatabaseID = -2; IGStatus = 7; IGMode = (decltype(IGMode))1; TimestampValid = true; \
  EarthRefModel = (decltype(EarthRefModel))0; FrameCntr = 42; TimeStampV3 = 0x01020304; \
  LastRcvdHostFrame = 12345; } };
SOF(CigiSOFV3) SOF(CigiSOFV3_2)

#define ENT(CLS) struct CLS##X : CLS { void fill() { \
  EntityID = 0x1234; EntityState = (decltype(EntityState))1; AttachState = (decltype(AttachState))1; \
  CollisionDetectEn = (decltype(CollisionDetectEn))1; InheritAlpha = (decltype(InheritAlpha))0; \
  GrndClamp = (decltype(GrndClamp))2; AnimationDir = (decltype(AnimationDir))1; \
  AnimationLoopMode = (decltype(AnimationLoopMode))1; AnimationState = (decltype(AnimationState))2; \
  SmoothingEn = true; Alpha = 200; EntityType = 0x0102; ParentID = 7; Roll = -10.5f; Pitch = 2.25f; \
  Yaw = 270.0f; LatOrXoff = 45.5; LonOrYoff = -122.25; AltOrZoff = 1500.125; } };
ENT(CigiEntityCtrlV3) ENT(CigiEntityCtrlV3_3)

struct ClampX : CigiConfClampEntityCtrlV3 { void fill() { EntityID = 77; Yaw = 123.5f; Lat = -33.875; Lon = 151.25; } };

#define RATE(CLS) struct CLS##X : CLS { void fill() { EntityID = 9; ArtPartIDV3 = 3; ApplyToArtPart = true; \
  CoordSys = (decltype(CoordSys))1; XRate = 1.5f; YRate = -2.5f; ZRate = 0.25f; RollRate = 10.0f; \
  PitchRate = -20.0f; YawRate = 30.0f; } };
RATE(CigiRateCtrlV3) RATE(CigiRateCtrlV3_2)

struct CelX : CigiCelestialCtrlV3 { void fill() { Hour = 14; Minute = 35; EphemerisEn = true; SunEn = true;
  MoonEn = false; StarEn = true; DateVld = true; Month = 6; Day = 21; Year = 2026; StarInt = 55.5f; } };
struct AtmX : CigiAtmosCtrlV3 { void fill() { AtmosEn = true; Humidity = 65; AirTemp = -5.5f; Visibility = 25000.0f;
  HorizWindSp = 12.5f; VertWindSp = -1.25f; WindDir = 270.0f; BaroPress = 1013.25f; } };

#define HHREQ(CLS) struct CLS##X : CLS { void fill() { HatHotID = 0xBEEF; ReqType = (decltype(ReqType))2; \
  SrcCoordSys = (decltype(SrcCoordSys))0; UpdatePeriod = 3; EntityID = 5; LatOrXoff = 47.25; \
  LonOrYoff = 11.375; AltOrZoff = 2000.5; } };
HHREQ(CigiHatHotReqV3) HHREQ(CigiHatHotReqV3_2)

#define HHRESP(CLS) struct CLS##X : CLS { void fill() { HatHotID = 0xBEEF; Valid = true; \
  ReqType = (decltype(ReqType))1; VldHat = false; VldHot = true; Hat = 0.0; Hot = 1234.5; HostFrame = 0xB; \
  Material = 0; NormAz = 0; NormEl = 0; } };
HHRESP(CigiHatHotRespV3) HHRESP(CigiHatHotRespV3_2)

#define HHX(CLS) struct CLS##X : CLS { void fill() { HatHotID = 0xBEEF; Valid = true; \
  VldHat = true; VldHot = true; Hat = 765.25; Hot = 1234.75; HostFrame = 9; Material = 0; \
  NormAz = 30.5f; NormEl = 80.25f; } };
HHX(CigiHatHotXRespV3) HHX(CigiHatHotXRespV3_2)

#define LOSSEG(CLS) struct CLS##X : CLS { void fill() { LosID = 0x0102; ReqType = (decltype(ReqType))1; \
  SrcCoordSys = (decltype(SrcCoordSys))0; DstCoordSys = (decltype(DstCoordSys))1; \
  ResponseCoordSys = (decltype(ResponseCoordSys))1; DestEntityIDValid = true; AlphaThresh = 128; \
  EntityID = 3; SrcXLat = 46.5; SrcYLon = 7.25; SrcZAlt = 3000.0; DstXLat = 10.5; DstYLon = -20.25; \
  DstZAlt = 5.0; Mask = 0xF0F00001; UpdatePeriod = 2; DestEntityID = 0x4321; } };
LOSSEG(CigiLosSegReqV3) LOSSEG(CigiLosSegReqV3_2)

#define LOSVEC(CLS) struct CLS##X : CLS { void fill() { LosID = 0x0A0B; ReqType = (decltype(ReqType))0; \
  SrcCoordSys = (decltype(SrcCoordSys))1; ResponseCoordSys = (decltype(ResponseCoordSys))0; \
  AlphaThresh = 10; EntityID = 4; VectAz = -45.5f; VectEl = -10.25f; MinRange = 1.5f; \
  MaxRange = 10000.0f; SrcXLat = 1.0; SrcYLon = 2.0; SrcZAlt = -3.0; Mask = 0xFFFFFFFF; UpdatePeriod = 4; } };
LOSVEC(CigiLosVectReqV3) LOSVEC(CigiLosVectReqV3_2)

#define LOSR(CLS) struct CLS##X : CLS { void fill() { LosID = 0x0102; Valid = true; EntityIDValid = false; \
  Visible = false; HostFrame = 5; RespCount = 1; EntityID = 0; Range = 4321.125; } };
LOSR(CigiLosRespV3) LOSR(CigiLosRespV3_2)

#define LOSX(CLS) struct CLS##X : CLS { void fill() { LosID = 0x0102; Valid = true; EntityIDValid = true; \
  RangeValid = true; Visible = false; IntersectionCoordSys = (decltype(IntersectionCoordSys))1; \
  HostFrame = 0xE; RespCount = 1; EntityID = 12; Range = 987.5; LatOrXoff = 10.5; LonOrYoff = -4.25; \
  AltOrZoff = 2.0; Red = 1; Green = 2; Blue = 3; Alpha = 4; Material = 0; NormalAz = -90.5f; NormalEl = 45.25f; } };
LOSX(CigiLosXRespV3) LOSX(CigiLosXRespV3_2)

struct VcX : CigiViewCtrlV3 { void fill() { ViewID = 2; GroupID = 1; XOffEn = YOffEn = ZOffEn = RollEn = PitchEn = YawEn = true;
  EntityID = 0; XOff = 1.5f; YOff = -0.5f; ZOff = 0.25f; Roll = 0.0f; Pitch = -5.0f; Yaw = 60.0f; } };
struct VdX : CigiViewDefV3 { void fill() { ViewID = 2; GroupID = 1; MirrorMode = (decltype(MirrorMode))2;
  FOVNearEn = FOVFarEn = FOVLeftEn = FOVRightEn = true; FOVTopEn = FOVBottomEn = false; ViewType = 5; Reorder = true;
  ProjectionType = (decltype(ProjectionType))1; PixelReplicateMode = (decltype(PixelReplicateMode))3;
  FOVNear = 0.5f; FOVFar = 50000.0f; FOVLeft = -30.0f; FOVRight = 30.0f; FOVTop = 20.0f; FOVBottom = -20.0f; } };

#define RUN(CLS, NAME, SPEC) { CLS p; p.fill(); pack(NAME, p, SPEC); }

int main() {
  CigiVersionID v30(3, 0), v31(3, 1), v32(3, 2), v33(3, 3);
  CigiAnimationTable at;
  RUN(CigiIGCtrlV3X, "ig_control_3_0", &v30)
  RUN(CigiIGCtrlV3_2X, "ig_control_3_2", &v32)
  RUN(CigiIGCtrlV3_3X, "ig_control_3_3", &v33)
  RUN(CigiSOFV3X, "start_of_frame_3_0", &v30)
  RUN(CigiSOFV3_2X, "start_of_frame_3_2", &v32)
  RUN(CigiSOFV3_2X, "start_of_frame_3_3", &v33)
  RUN(CigiEntityCtrlV3X, "entity_control_3_0", &at)
  RUN(CigiEntityCtrlV3_3X, "entity_control_3_3", &at)
  RUN(ClampX, "conformal_clamped_3_0", &v30)
  RUN(CigiRateCtrlV3X, "rate_control_3_0", &v30)
  RUN(CigiRateCtrlV3_2X, "rate_control_3_2", &v32)
  RUN(CelX, "celestial_3_0", NULL)
  RUN(AtmX, "atmosphere_3_0", NULL)
  RUN(CigiHatHotReqV3X, "hat_hot_request_3_0", &v30)
  RUN(CigiHatHotReqV3_2X, "hat_hot_request_3_2", &v32)
  RUN(CigiHatHotRespV3X, "hat_hot_response_3_0", &v30)
  RUN(CigiHatHotRespV3_2X, "hat_hot_response_3_2", &v32)
  RUN(CigiHatHotXRespV3X, "hat_hot_extended_response_3_0", &v30)
  RUN(CigiHatHotXRespV3_2X, "hat_hot_extended_response_3_2", &v32)
  RUN(CigiLosSegReqV3X, "los_segment_request_3_0", &v30)
  RUN(CigiLosSegReqV3_2X, "los_segment_request_3_2", &v32)
  RUN(CigiLosVectReqV3X, "los_vector_request_3_0", &v30)
  RUN(CigiLosVectReqV3_2X, "los_vector_request_3_2", &v32)
  RUN(CigiLosRespV3X, "los_response_3_0", &v30)
  RUN(CigiLosRespV3_2X, "los_response_3_2", &v32)
  RUN(CigiLosXRespV3X, "los_extended_response_3_0", &v30)
  RUN(CigiLosXRespV3_2X, "los_extended_response_3_2", &v32)
  RUN(VcX, "view_control_3_0", NULL)
  RUN(VdX, "view_definition_3_0", NULL)
  return 0;
}
