// The `fivebar` executable: signal hygiene, then the front end (cli/main.cpp).

#include "cli.hpp"
#include "fivebar/io.hpp"

int main(int argc, char** argv) {
  // SIGINT / SIGTERM / SIGHUP / SIGPIPE remove the temporaries of unfinished output files.
  fivebar::install_interrupt_cleanup();
  return fivebar::cli::main(argc, argv);
}
