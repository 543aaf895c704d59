#include "apps/commands.hpp"

int main(int argc, char** argv) { return dicesim::run_cli(argc, argv); }
