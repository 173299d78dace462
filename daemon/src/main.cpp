// handtrackd: the daemon with the production sources (SPEC.md "Sources").
#include "handtrackd.hpp"

int main(int argc, char** argv) { return handtrack::daemon::run_handtrackd(argc, argv, handtrack::daemon::make_source); }
