// policy_sha256: the digest of a whole policy archive (code, constants, weights, metadata). The
// definition is in python/ernest_cpp/rl/policy_file.py, which computes the same bytes: every
// record but .data/serialization_id, uncompressed, in byte-wise name order, each as name '\n'
// size '\n' bytes, the metadata record with the digest's own value replaced by 64 '0'.
#include <caffe2/serialize/inline_container.h>
#include <openssl/evp.h>

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include "ernest/runtime/policy.hpp"
#include "sha256_hex.hpp"

namespace ernest::runtime {

std::string policy_sha256(const std::string& path, const std::string& digest_in_metadata) {
  const std::string metadata_record = std::string("extra/") + Policy::kMetadataFile;
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx(EVP_MD_CTX_new(), &EVP_MD_CTX_free);
  if (!ctx || EVP_DigestInit_ex(ctx.get(), EVP_sha256(), nullptr) != 1)
    throw std::runtime_error("policy_sha256: OpenSSL SHA-256 unavailable");
  std::vector<std::string> names;
  try {
    caffe2::serialize::PyTorchStreamReader reader(path);
    names = reader.getAllRecords();
    std::sort(names.begin(), names.end());  // char_traits<char>: byte-wise, like Python's bytes
    if (std::adjacent_find(names.begin(), names.end()) != names.end())
      throw PolicyError(PolicyError::Kind::CorruptFile,
                        path + ": record " + *std::adjacent_find(names.begin(), names.end()) +
                            " appears twice in the archive");
    for (const std::string& name : names) {
      if (name == ".data/serialization_id") continue;  // derived by torch from the other records
      auto [data, size] = reader.getRecord(name);
      std::string bytes(static_cast<const char*>(data.get()), size);
      if (name == metadata_record) {
        const size_t at = bytes.find(digest_in_metadata);
        if (digest_in_metadata.empty() || at == std::string::npos ||
            bytes.find(digest_in_metadata, at + 1) != std::string::npos)
          throw PolicyError(PolicyError::Kind::ChecksumMismatch,
                            path + ": the policy_sha256 value must appear exactly once in " +
                                Policy::kMetadataFile);
        bytes.replace(at, digest_in_metadata.size(), std::string(digest_in_metadata.size(), '0'));
      }
      const std::string head = name + "\n" + std::to_string(bytes.size()) + "\n";
      EVP_DigestUpdate(ctx.get(), head.data(), head.size());
      EVP_DigestUpdate(ctx.get(), bytes.data(), bytes.size());
    }
  } catch (const PolicyError&) {
    throw;
  } catch (const std::exception& e) {  // c10::Error from the zip reader
    throw PolicyError(PolicyError::Kind::CorruptFile, path + ": cannot read the archive's records (" +
                                                          std::string(e.what()).substr(0, 200) + ")");
  }
  return finish_hex(ctx.get());
}

}  // namespace ernest::runtime
