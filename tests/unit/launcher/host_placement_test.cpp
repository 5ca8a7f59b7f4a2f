// Placing a launch on hosts: which address of this machine the launcher speaks from, and a
// child's argv through its host's prefix (quoted for the remote shell after ssh).

#include "sensornet/launcher/host_placement.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "sensornet/core/input_error.hpp"

namespace sensornet::launcher {
namespace {

using Argv = std::vector<std::string>;

// 127.0.0.1/8 and 10.78.0.254/24.
const std::vector<LocalAddress> kLocal = {{0x7f000001u, 0xff000000u, "127.0.0.1"},
                                          {0x0a4e00feu, 0xffffff00u, "10.78.0.254"}};

TEST(HostPlacement, DottedQuadsAreReadInHostOrder) {
  EXPECT_EQ(ipv4Number("10.78.0.254"), 0x0a4e00feu);
  EXPECT_EQ(ipv4Number("255.255.255.0"), 0xffffff00u);
  EXPECT_EQ(ipv4Number("not an address"), 0u);
}

TEST(HostPlacement, TheLauncherSpeaksFromItsAddressOnTheCoordinatorsNetwork) {
  EXPECT_EQ(chooseLauncherAddress(kLocal, std::nullopt, "10.78.0.1", "hosts.yaml"), "10.78.0.254");
  EXPECT_EQ(chooseLauncherAddress(kLocal, std::nullopt, "127.0.0.9", "hosts.yaml"), "127.0.0.1");
}

TEST(HostPlacement, NoInterfaceOnThatNetworkIsOneLineNamingTheFile) {
  try {
    (void)chooseLauncherAddress(kLocal, std::nullopt, "192.168.1.5", "hosts.yaml");
    FAIL() << "no interface on 192.168.1.0/24";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("hosts.yaml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("launcher.address"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("192.168.1.5"), std::string::npos) << e.what();
  }
}

TEST(HostPlacement, AGivenAddressMustBeThisMachines) {
  EXPECT_EQ(chooseLauncherAddress(kLocal, std::string("127.0.0.1"), "10.78.0.1", "h.yaml"),
            "127.0.0.1")
      << "given wins over the coordinator's network";
  EXPECT_THROW((void)chooseLauncherAddress(kLocal, std::string("10.78.0.9"), "10.78.0.1", "h.yaml"),
               InputError);
}

TEST(HostPlacement, APrefixRunsTheArgvAsGiven) {
  EXPECT_EQ(prefixedArgv({"/usr/sbin/ip", "netns", "exec", "sn-e1"}, {"/bin/agent", "--x", "a b"}),
            (Argv{"/usr/sbin/ip", "netns", "exec", "sn-e1", "/bin/agent", "--x", "a b"}));
  EXPECT_EQ(prefixedArgv({}, {"/bin/agent"}), (Argv{"/bin/agent"}));
}

TEST(HostPlacement, AfterSshEveryWordIsQuotedForTheRemoteShell) {
  EXPECT_EQ(prefixedArgv({"/usr/bin/ssh", "-tt", "pi@edge"}, {"/bin/agent", "<a b='c'/>"}),
            (Argv{"/usr/bin/ssh", "-tt", "pi@edge", "'/bin/agent'", "'<a b='\\''c'\\''/>'"}));
}

TEST(HostPlacement, ShellQuotingClosesReopensAroundAQuote) {
  EXPECT_EQ(shellQuoted(""), "''");
  EXPECT_EQ(shellQuoted("it's"), "'it'\\''s'");
  EXPECT_EQ(shellQuoted("$HOME; rm"), "'$HOME; rm'");
}

// The shell reads a printed line back as the words it was made of (checked by /bin/sh itself,
// not by the quoting rules restated), and plain words are printed bare.
TEST(HostPlacement, APrintedCommandLineIsReadBackAsItsWords) {
  const Argv words = {"--run-id", "run-34", "--cyclone-config", "/tmp/a b/c.xml",
                      "--security", "it's $HOME", "--x", "", "a;b"};
  const std::string line = shellLine(words);
  EXPECT_EQ(shellLine({"--run-id", "run-34", "--domain-id", "34"}),
            "--run-id run-34 --domain-id 34");
  FILE* shell = ::popen(("/bin/sh -c 'for w; do printf \"%s\\n\" \"$w\"; done' sh " + line)
                            .c_str(), "r");
  ASSERT_NE(shell, nullptr);
  Argv read;
  std::string current;
  for (int c = std::fgetc(shell); c != EOF; c = std::fgetc(shell)) {
    if (c == '\n') {
      read.push_back(current);
      current.clear();
    } else {
      current += static_cast<char>(c);
    }
  }
  EXPECT_EQ(::pclose(shell), 0);
  EXPECT_EQ(read, words) << line;
}

}  // namespace
}  // namespace sensornet::launcher
