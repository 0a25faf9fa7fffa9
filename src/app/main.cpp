// The `epa` command: one executable, one subcommand per job.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <string>

#include "app/certs_command.hpp"
#include "app/commission_command.hpp"
#include "app/design_command.hpp"
#include "app/diagnose_command.hpp"
#include "app/excite_command.hpp"
#include "app/faults_command.hpp"
#include "app/identify_command.hpp"
#include "app/plant_server_command.hpp"
#include "app/records_command.hpp"
#include "app/registers_command.hpp"
#include "app/serve_command.hpp"
#include "app/simulate_command.hpp"
#include "app/tuning_command.hpp"
#include "core/version.hpp"

int main(int argc, char** argv) {
  CLI::App app{"epa: electro-pneumatic actuator controller appliance (pole placement with feed-forward "
               "inverse dead-zone compensation)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "epa " + std::string(epa::core::kVersion));
  epa::app::SimulateOptions simulate;
  epa::app::DesignOptions design;
  epa::app::ExciteOptions excite;
  epa::app::IdentifyOptions identify;
  epa::app::ServeOptions serve;
  epa::app::PlantServerOptions plant_server;
  epa::app::RegistersOptions registers;
  epa::app::TuningOptions tuning;
  epa::app::add_serve_command(app, serve);
  epa::app::add_plant_server_command(app, plant_server);
  epa::app::add_registers_command(app, registers);
  epa::app::add_simulate_command(app, simulate);
  epa::app::add_design_command(app, design);
  epa::app::add_excite_command(app, excite);
  epa::app::add_identify_command(app, identify);
  epa::app::add_tuning_command(app, tuning);
  epa::app::FaultsOptions faults;
  CLI::App* faults_command = epa::app::add_faults_command(app, faults);
  epa::app::CommissionOptions commission;
  epa::app::add_commission_command(app, commission);
  epa::app::RecordsOptions records;
  CLI::App* records_command = epa::app::add_records_command(app, records);
  epa::app::DiagnoseOptions diagnose;
  epa::app::add_diagnose_command(app, diagnose);
  epa::app::CertsOptions certs;
  CLI::App* certs_command = epa::app::add_certs_command(app, certs);
  // CLI11 answers a mistyped command with "A subcommand is required"; name it and the commands.
  std::string commands;
  bool known = false;
  for (CLI::App* command : app.get_subcommands({})) {
    commands += (commands.empty() ? "" : ", ") + command->get_name();
    known = known || (argc > 1 && command->check_name(argv[1]));
  }
  if (argc > 1 && argv[1][0] != '-' && !known) {
    std::cerr << "epa: '" << argv[1] << "' is not a command; the commands: " << commands << " (epa --help)\n";
    return 109;  // CLI11's exit code for a missing or unknown subcommand
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    if (app.got_subcommand("simulate")) return epa::app::run_simulate(simulate, std::cout, std::cerr);
    if (app.got_subcommand("design")) return epa::app::run_design(design, std::cout, std::cerr);
    if (app.got_subcommand("excite")) return epa::app::run_excite(excite, std::cout, std::cerr);
    if (app.got_subcommand("identify")) return epa::app::run_identify(identify, std::cout, std::cerr);
    if (app.got_subcommand("commission")) return epa::app::run_commission(commission, std::cout, std::cerr);
    if (app.got_subcommand("diagnose")) return epa::app::run_diagnose(diagnose, std::cout, std::cerr);
    if (app.got_subcommand("serve")) return epa::app::run_serve(serve, std::cerr);
    if (app.got_subcommand("registers")) return epa::app::run_registers(registers, std::cout, std::cerr);
    if (app.got_subcommand("tuning")) return epa::app::run_tuning(app, tuning, std::cout, std::cerr);
    if (app.got_subcommand(records_command)) return epa::app::run_records(records, std::cout, std::cerr);
    if (app.got_subcommand(certs_command)) return epa::app::run_certs(certs, std::cout, std::cerr);
    if (app.got_subcommand(faults_command)) return epa::app::run_faults(faults, std::cout, std::cerr);
    if (app.got_subcommand("plant-server")) return epa::app::run_plant_server(plant_server, std::cout, std::cerr);
  } catch (const std::exception& e) {  // third-party code (CLI11, JSON, filesystem) at the edge
    std::cerr << "epa: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
