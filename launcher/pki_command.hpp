#pragma once
// `sensornet pki init DIR [--force] [--days N] [--key ec|rsa] [--rsa-bits B]`: the files of a
// secured run (DDS Security, issue 12 part 3), made with the openssl program:
//
//   DIR/ca.pem, ca.key            the certificate authority (identity CA and permissions CA)
//   DIR/governance.xml, .p7s      domains 0..230: only authenticated participants join; discovery
//                                 and liveliness encrypted; every topic read- and write-access
//                                 controlled, its payload encrypted and its submessages signed
//   DIR/<role>/identity.pem       the role's certificate (CN=<role>, O=sensornet), key.pem
//   DIR/<role>/permissions.xml, .p7s   what the role may publish and subscribe, signed by the CA
//
// Roles (dds::SecurityRole): coordinator, fusion_center, sensor, operator (replan, status,
// watch), launcher. Every program given `--security DIR` presents its own role's files.
// DIR that exists and is not empty is refused unless --force; openssl missing is one line,
// exit 2, as is any other bad input.

#include "sensornet/io/command_line.hpp"

namespace sensornet::launcher {

Subcommand addPkiCommand(CLI::App& app);

}  // namespace sensornet::launcher
