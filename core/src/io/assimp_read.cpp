/* assimp restricted to the readers that claim a file's extension (see assimp_read.h). */
#include "io/assimp_read.h"

#include <tunetrace/file.h>

#include <assimp/BaseImporter.h>
#include <assimp/DefaultIOSystem.h>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <cstdio>
#include <cstring>
#include <new>
#include <set>
#include <string>
#include <strings.h>
#include <vector>

struct tt__assimp {
  Assimp::Importer importer;
};

/* assimp's file system with the library's input check: every file an importer opens (the
 * mesh, an OBJ's .mtl, a glTF's .bin buffers) is refused unless it is a regular file, so a
 * FIFO or a device named inside a mesh is a missing file to assimp, never a hang. */
class tt__regular_io : public Assimp::DefaultIOSystem {
public:
  bool Exists(const char *file) const override {
    return file && tt_file_check_regular(file, NULL) == TT_OK;
  }
  Assimp::IOStream *Open(const char *file, const char *mode = "rb") override {
    if (!file || !mode) return nullptr;
    if (!std::strchr(mode, 'w') && !std::strchr(mode, 'a') &&
        tt_file_check_regular(file, NULL) != TT_OK)
      return nullptr;
    return Assimp::DefaultIOSystem::Open(file, mode);
  }
};

/* assimp's own test (Importer::ReadFile): the whole path ends with "." + ext, any case. */
static bool tt__claims(const std::string &path, const std::string &ext) {
  std::string dotted = "." + ext;
  return dotted.size() <= path.size() &&
         strcasecmp(path.c_str() + path.size() - dotted.size(), dotted.c_str()) == 0;
}

extern "C" tt__assimp_result tt__assimp_read(const char *file, unsigned flags, tt__assimp **handle,
                                             const struct aiScene **scene, char *why, size_t n) {
  *handle = nullptr;
  *scene = nullptr;
  if (n) why[0] = '\0';
  tt__assimp *h = nullptr;
  try {
    h = new tt__assimp;
    Assimp::Importer &imp = h->importer;
    imp.SetIOHandler(new tt__regular_io); /* the importer owns and deletes it */
    const std::string path(file);
    std::vector<Assimp::BaseImporter *> others;
    size_t claimed = 0;
    for (size_t i = 0; i < imp.GetImporterCount(); i++) {
      Assimp::BaseImporter *reader = imp.GetImporter(i);
      std::set<std::string> exts;
      reader->GetExtensionList(exts);
      bool mine = false;
      for (const std::string &e : exts) mine = mine || tt__claims(path, e);
      if (mine) claimed++;
      else others.push_back(reader);
    }
    if (claimed == 0) {
      delete h;
      return TT__ASSIMP_UNKNOWN_EXTENSION;
    }
    /* UnregisterLoader only drops the pointer; the Importer deletes what is registered */
    for (Assimp::BaseImporter *reader : others) {
      imp.UnregisterLoader(reader);
      delete reader;
    }
    const aiScene *sc = imp.ReadFile(path, flags);
    if (!sc) {
      if (n) snprintf(why, n, "%s", imp.GetErrorString());
      delete h;
      return TT__ASSIMP_FAILED;
    }
    *scene = sc;
    *handle = h;
    return TT__ASSIMP_OK;
  } catch (const std::bad_alloc &) {
    delete h;
    return TT__ASSIMP_OUT_OF_MEMORY;
  } catch (const std::exception &e) {
    if (n) snprintf(why, n, "%s", e.what());
    delete h;
    return TT__ASSIMP_FAILED;
  } catch (...) {
    if (n) snprintf(why, n, "unknown exception in assimp");
    delete h;
    return TT__ASSIMP_FAILED;
  }
}

extern "C" tt__assimp_result tt__assimp_validate(tt__assimp *handle, char *why, size_t n) {
  if (n) why[0] = '\0';
  try {
    if (handle->importer.ApplyPostProcessing(aiProcess_ValidateDataStructure)) return TT__ASSIMP_OK;
    if (n) snprintf(why, n, "%s", handle->importer.GetErrorString());
    return TT__ASSIMP_FAILED;
  } catch (const std::bad_alloc &) {
    return TT__ASSIMP_OUT_OF_MEMORY;
  } catch (const std::exception &e) {
    if (n) snprintf(why, n, "%s", e.what());
    return TT__ASSIMP_FAILED;
  } catch (...) {
    if (n) snprintf(why, n, "unknown exception in assimp");
    return TT__ASSIMP_FAILED;
  }
}

extern "C" void tt__assimp_free(tt__assimp *handle) { delete handle; }
