// One line of text per received message, as visvol-echo prints it: the
// message name, then key=value fields with units in the keys; or (--json) one
// JSON object per line, {"topic": ..., fields with the message's own names}.
#pragma once

#include <string>

#include "drivers/dds/message_codec.hpp"

namespace visvol::echo {

// with_vertices: one more line per vertex, "  [i] x_m y_m z_m visibility clearance_m".
std::string format_path_update(const visvol_msgs_msg_dds__PathUpdate_& m, bool with_vertices);
std::string format_health(const visvol_msgs_msg_dds__LoopHealth_& m);
std::string format_device_status(const visvol_msgs_msg_dds__DeviceStatus_& m);
std::string format_terrain(const visvol_msgs_msg_dds__TerrainInfo_& m);
std::string format_catalogue(const visvol_msgs_msg_dds__TerrainCatalogue_& m);
std::string format_thumbnail(const sensor_msgs_msg_dds__CompressedImage_& m);
std::string format_ack(const visvol_msgs_msg_dds__CommandAck_& m);

// The same messages as one line of JSON each (strings that are not UTF-8 get
// U+FFFD; enumerations by name, "unknown" outside them; stamps in ns since
// the Unix epoch). with_vertices: "positions_m" [[x, y, z]...],
// "visibility" and "clearance_m" arrays.
std::string json_path_update(const visvol_msgs_msg_dds__PathUpdate_& m, bool with_vertices);
std::string json_health(const visvol_msgs_msg_dds__LoopHealth_& m);
std::string json_device_status(const visvol_msgs_msg_dds__DeviceStatus_& m);
std::string json_terrain(const visvol_msgs_msg_dds__TerrainInfo_& m);
std::string json_catalogue(const visvol_msgs_msg_dds__TerrainCatalogue_& m);
std::string json_thumbnail(const sensor_msgs_msg_dds__CompressedImage_& m);
std::string json_ack(const visvol_msgs_msg_dds__CommandAck_& m);

}  // namespace visvol::echo
