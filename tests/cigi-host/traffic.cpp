// The `traffic` script: other entities around the ownship, as a host sends them (issue 18).
// Counted in host frames k from the first Start of Frame:
//   k >= 2         entity 1 (type 1234, not configured: the IG's default model) 400 m ahead of
//                  the ownship, flying north 1 m per message; entity 2 (type 77) attached to it
//                  30 m to its right; entity 3, a ground vehicle (Conformal Clamped Entity
//                  Control, once) 300 m north-east, driven on by one Rate Control (15 m/s
//                  forward, body axes);
//   [standby_from, standby_to)   entity 1 in Standby (kept, not drawn);
//   k >= destroy   entity 1 destroyed (its child 2 goes with it); entity 3 stays.
#include <cstdio>

#include <CigiConfClampEntityCtrlV3.h>
#include <CigiEntityCtrlV3_3.h>
#include <CigiRateCtrlV3_2.h>

#include "host.h"

void traffic(Link& link, CigiOutgoingMsg& out, long k) {
  const Options& o = link.opt;
  if (k < 2) return;
  const double lat0 = link.ownship.GetLat(), lon0 = link.ownship.GetLon();
  const double alt0 = link.ownship.GetAlt();
  if (k <= o.destroy_frame) {
    CigiEntityCtrlV3_3 lead;
    lead.SetEntityID(1);
    lead.SetEntityType(1234);
    const bool standby = k >= o.standby_from && k < o.standby_to;
    lead.SetEntityState(k == o.destroy_frame ? CigiBaseEntityCtrl::Remove
                        : standby            ? CigiBaseEntityCtrl::Standby
                                             : CigiBaseEntityCtrl::Active);
    lead.SetAttachState(CigiBaseEntityCtrl::Detach);
    // 400 m ahead (north), then 1 m further per message (1 m ≈ 9e-6° of latitude).
    lead.SetLat(lat0 + (400.0 + static_cast<double>(k - 2)) / 111200.0);
    lead.SetLon(lon0);
    lead.SetAlt(alt0);
    lead.SetYaw(0);
    out << lead;
    if (k < o.destroy_frame) {
      CigiEntityCtrlV3_3 wing;
      wing.SetEntityID(2);
      wing.SetEntityType(77);
      wing.SetEntityState(CigiBaseEntityCtrl::Active);
      wing.SetAttachState(CigiBaseEntityCtrl::Attach);
      wing.SetParentID(1);
      wing.SetXoff(0);
      wing.SetYoff(30);
      wing.SetZoff(0);
      out << wing;
    }
  }
  if (k == 2) {
    CigiConfClampEntityCtrlV3 truck;
    truck.SetEntityID(3);
    truck.SetYaw(45);
    truck.SetLat(lat0 + 212.0 / 111200.0);
    truck.SetLon(lon0 + 212.0 / 75400.0);
    out << truck;
    CigiRateCtrlV3_2 drive;
    drive.SetEntityID(3);
    drive.SetApplyToArtPart(false);
    drive.SetArtPartID(0);
    drive.SetCoordSys(CigiBaseRateCtrl::Local);
    drive.SetXRate(15);
    drive.SetYRate(0);
    drive.SetZRate(0);
    drive.SetRollRate(0);
    drive.SetPitchRate(0);
    drive.SetYawRate(0);
    out << drive;
  }
  if (k == 2 || k == o.destroy_frame)
    Json()
        .str("sent", k == 2 ? "traffic_created" : "traffic_destroyed")
        .integer("n", link.counts.sent)
        .integer("k", k)
        .print();
}
