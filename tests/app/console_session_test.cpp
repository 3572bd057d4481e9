// The console's sessions: where a failed terrain switch goes back to.
#include <gtest/gtest.h>

#include "app/console.hpp"

namespace visvol::app {
namespace {

// A switch away from a catalogue's pack (in no --terrain list) that cannot
// start goes back to that pack's file: it went back to the broken pack, failed
// again and ended the console.
TEST(ConsoleSession, AFailedSwitchGoesBackToThePackItLeftFromTheCatalogueToo) {
  ConsoleOptions failed;
  failed.pack = "/packs/active.vvp";  // damaged after start-up
  failed.catalogue = "/catalogue";
  failed.switched_from = "small";
  failed.switched_from_path = "/catalogue/small.vvp";
  const ConsoleOptions back = session_after_failed_switch(failed, "truncated");
  EXPECT_EQ(back.pack, "/catalogue/small.vvp");
  EXPECT_TRUE(back.switched_from.empty());
  EXPECT_TRUE(back.switched_from_path.empty());
  EXPECT_EQ(back.switch_failed, "active: truncated");

  // from a --terrain pack: the same, and the broken one leaves the list
  ConsoleOptions listed;
  listed.pack = "/packs/b.vvp";
  listed.terrains = {"/packs/a.vvp", "/packs/c.vvp"};
  listed.switched_from = "a";
  listed.switched_from_path = "/packs/a.vvp";
  const ConsoleOptions again = session_after_failed_switch(listed, "bad");
  EXPECT_EQ(again.pack, "/packs/a.vvp");
  EXPECT_EQ(again.terrains, std::vector<std::string>{"/packs/c.vvp"});
}

}  // namespace
}  // namespace visvol::app
