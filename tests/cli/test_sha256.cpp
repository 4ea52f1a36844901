// SHA-256 (cli/shell/sha256.hpp) against FIPS 180-4's examples and NIST's long message, fed whole
// and in pieces that straddle its 64-byte blocks.
#include <sha256.hpp>

#include <doctest/doctest.h>

#include <string>

TEST_CASE("SHA-256: FIPS 180-4's examples, the empty message and a million 'a'") {
  using wlx::cli::sha256_hex;
  CHECK(sha256_hex("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  CHECK(sha256_hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq") ==
        "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  CHECK(sha256_hex(std::string(1000000, 'a')) == "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST_CASE("SHA-256: a message fed in pieces of any size gives the digest of the whole") {
  std::string message;
  for (int k = 0; k < 1000; ++k) message += static_cast<char>((k * 37 + 11) & 0xff);
  const std::string whole = wlx::cli::sha256_hex(message);
  for (const std::size_t piece : {1u, 3u, 55u, 56u, 63u, 64u, 65u, 127u, 999u}) {
    CAPTURE(piece);
    wlx::cli::Sha256 h;
    for (std::size_t at = 0; at < message.size(); at += piece) h.add(std::string_view(message).substr(at, piece));
    CHECK(h.hex() == whole);
  }
}
