// Registration functions of the subcommands, one per file (cmd_<name>.cpp).
#pragma once

#include "command.hpp"

namespace usvfdi::app {

void register_replay_command(CommandRegistry& registry);   // cmd_replay.cpp
void register_sim_command(CommandRegistry& registry);      // cmd_sim.cpp
void register_vessels_command(CommandRegistry& registry);  // cmd_vessels.cpp
void register_plot_command(CommandRegistry& registry);     // cmd_plot.cpp (matplotlib)
#ifdef USV_FDI_APP_WITH_DDS
void register_run_command(CommandRegistry& registry);        // cmd_run.cpp (DDS service)
void register_monitor_command(CommandRegistry& registry);    // cmd_monitor.cpp (DDS subscriber)
void register_health_command(CommandRegistry& registry);     // cmd_health.cpp (health check)
void register_bridge_command(CommandRegistry& registry);     // cmd_bridge.cpp (BAM over 61162-450)
void register_emulate_command(CommandRegistry& registry);    // cmd_emulate.cpp (fleet emulator)
void register_ros2_command(CommandRegistry& registry);       // cmd_ros2.cpp (ROS 2 via Fast DDS)
void register_dashboard_command(CommandRegistry& registry);  // cmd_dashboard.cpp (browser board)
#endif

}  // namespace usvfdi::app
