// Finishing a SHA-256 digest as lowercase hex: the policy file's two digests (weights and the
// whole archive) end the same way. Private to the runtime library.
#pragma once

#include <openssl/evp.h>

#include <string>

namespace ernest::runtime {

inline std::string finish_hex(EVP_MD_CTX* ctx) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  EVP_DigestFinal_ex(ctx, md, &len);
  static const char* hex = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < len; ++i) {
    out += hex[md[i] >> 4];
    out += hex[md[i] & 15];
  }
  return out;
}

}  // namespace ernest::runtime
